// SPDX-License-Identifier: MIT
// The viewer's server in process, driven by a WebSocket client (Boost.Beast) as the page would.
#include "uvr/server/view_server.h"

#include <gmock/gmock.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/resource.h>
#include <unistd.h>
#include <atomic>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <thread>

#include "test_meshes.h"
#include "test_support.h"
#include "uvr/core/error.h"
#include "uvr/dist/decompose.h"
#include "uvr/dist/in_process_communicator.h"
#include "uvr/mesh/io/exodus.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/native.h"
#include "uvr/render/image_metrics.h"
#include "uvr/server/web_assets.h"

#ifdef UVR_HAVE_NETCDF
#include "exodus_file_writer.h"
#endif

namespace uvr::server {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace std::chrono_literals;

/// A mesh with a point field "f" and a cell field "g" of other ranges.
std::shared_ptr<Mesh> twoFieldMesh() {
    auto m = std::make_shared<Mesh>(testing::makeHexGrid(
        6, -1.f, 1.f, [](Vec3f p) { return p.x + 2.f * p.y; }, 0.2f));
    Field g{"g", Association::Cell, 1, {}};
    for (std::size_t c = 0; c < m->cellCount(); ++c) g.values.push_back(100.f + float(c));
    m->fields.push_back(g);
    return m;
}

/// The tests' scenes: the CPU, leaves of 64 cells, and 64x48 viridis frames of scene.bounds over
/// [-3, 3].
void useTestFrames(ViewScene& scene) {
    scene.rendererOptions.device = Device::Cpu;
    scene.rendererOptions.leafCells = 64;
    ViewState& s = scene.initial;
    s.camera = resetCamera(scene.bounds, 64.f / 48.f);
    s.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(s.tf, "0:0,1:0.6");
    s.range = {-3.f, 3.f};
    s.width = 64;
    s.height = 48;
}

/// A server on a free port of 127.0.0.1 over the two-field mesh, on the CPU, 64x48 frames.
std::unique_ptr<ViewServer> startServer(ServerOptions o = {}, LogFn log = {}) {
    ViewScene scene;
    scene.file = "grid.vtk";
    scene.mesh = twoFieldMesh();
    scene.bounds = scene.mesh->bounds();
    useTestFrames(scene);
    ViewState& s = scene.initial;
    s.settings["opacity_unit"] = 0.5;
    scene.commandFlags = {"--sample-distance", "0.01"};
    o.port = 0;
    auto server = std::make_unique<ViewServer>(std::move(scene), o, std::move(log));
    server->start();
    return server;
}

/// A WebSocket client with timeouts on its own io_context.
class Client {
public:
    /// Connects to /ws?token=TOKEN; throws beast::system_error when the handshake fails. A
    /// receiveBuffer above 0 sets the socket's receive buffer (bytes) before connecting.
    Client(std::uint16_t port, const std::string& token, int receiveBuffer = 0) : ws_(ioc_) {
        const tcp::endpoint to(net::ip::make_address("127.0.0.1"), port);
        ws_.next_layer().open(to.protocol());
        if (receiveBuffer > 0)
            ws_.next_layer().set_option(net::socket_base::receive_buffer_size(receiveBuffer));
        ws_.next_layer().connect(to);
        ws_.handshake("127.0.0.1:" + std::to_string(port), "/ws?token=" + token);
    }

    void send(const nlohmann::json& j) { sendText(j.dump()); }
    void sendText(const std::string& text) {
        ws_.text(true);
        ws_.write(net::buffer(text));
    }
    void sendBinary(const std::string& bytes) {
        ws_.binary(true);
        ws_.write(net::buffer(bytes));
    }

    /// The next message (text JSON or, for a binary one, {"binary": size}); null on timeout
    /// (the read stays pending for the next call) or a closed connection (closed() says which).
    nlohmann::json next(std::chrono::milliseconds timeout = 10s) {
        if (closed_) return nullptr;
        if (!reading_) {
            reading_ = true;
            done_ = false;
            buffer_.clear();
            ws_.async_read(buffer_, [this](beast::error_code ec, std::size_t) {
                done_ = true;
                error_ = ec;
            });
        }
        ioc_.restart();
        ioc_.run_for(timeout);
        if (!done_) return nullptr;
        reading_ = false;
        if (error_) {
            closed_ = true;
            return nullptr;
        }
        if (ws_.got_binary()) {
            lastBinary_ = beast::buffers_to_string(buffer_.data());
            return nlohmann::json{{"binary", lastBinary_.size()}};
        }
        return nlohmann::json::parse(beast::buffers_to_string(buffer_.data()));
    }

    /// Messages until one of `type` arrives (null on timeout).
    nlohmann::json until(const std::string& type, std::chrono::milliseconds timeout = 20s) {
        const auto end = std::chrono::steady_clock::now() + timeout;
        while (std::chrono::steady_clock::now() < end) {
            nlohmann::json j = next(std::chrono::duration_cast<std::chrono::milliseconds>(
                end - std::chrono::steady_clock::now()));
            if (j.is_null()) return nullptr;
            if (j.contains("type") && j["type"] == type) return j;
            seen_.push_back(j);
        }
        return nullptr;
    }

    /// The next frame's description, its image read (lastBinary()).
    nlohmann::json frame(std::chrono::milliseconds timeout = 20s) {
        nlohmann::json f = until("frame", timeout);
        if (!f.is_null()) {
            const nlohmann::json image = next();
            EXPECT_TRUE(image.contains("binary")) << image.dump();
        }
        return f;
    }

    const std::string& lastBinary() const { return lastBinary_; }
    const std::vector<nlohmann::json>& seen() const { return seen_; }
    bool closed() const { return closed_; }

private:
    net::io_context ioc_;
    websocket::stream<tcp::socket> ws_;
    std::string lastBinary_;
    std::vector<nlohmann::json> seen_;
    beast::flat_buffer buffer_;
    bool reading_ = false, done_ = false, closed_ = false;
    beast::error_code error_;
};

/// Status of a plain HTTP GET of target, with optional Cookie header.
int httpGet(std::uint16_t port, const std::string& target, const std::string& cookie = "",
            std::string* setCookie = nullptr, std::string* body = nullptr) {
    net::io_context ioc;
    tcp::socket socket(ioc);
    tcp::resolver resolver(ioc);
    net::connect(socket, resolver.resolve("127.0.0.1", std::to_string(port)));
    http::request<http::empty_body> req{http::verb::get, target, 11};
    req.set(http::field::host, "127.0.0.1");
    if (!cookie.empty()) req.set(http::field::cookie, cookie);
    http::write(socket, req);
    beast::flat_buffer buffer;
    http::response<http::string_body> res;
    http::read(socket, buffer, res);
    if (setCookie) setCookie->assign(res[http::field::set_cookie]);
    if (body) *body = res.body();
    return res.result_int();
}

bool isPng(const std::string& b) {
    return b.size() > 8 && b.compare(1, 3, "PNG") == 0;
}
bool isJpeg(const std::string& b) {
    return b.size() > 2 && static_cast<unsigned char>(b[0]) == 0xFF &&
           static_cast<unsigned char>(b[1]) == 0xD8;
}

TEST(ViewServer, InfoThenAFullFrameOfTheStartingState) {
    auto server = startServer();
    EXPECT_THAT(server->url(), HasSubstr("http://127.0.0.1:" + std::to_string(server->port()) +
                                         "/?token=" + server->token()));
    EXPECT_EQ(server->token().size(), 32u);
    Client c(server->port(), server->token());
    const nlohmann::json info = c.next();
    ASSERT_EQ(info["type"], "info") << info.dump();
    EXPECT_EQ(info["file"], "grid.vtk");
    EXPECT_EQ(info["cells"], 216);
    ASSERT_EQ(info["fields"].size(), 2u);
    EXPECT_EQ(info["fields"][0]["name"], "f");
    EXPECT_TRUE(info["fields"][0]["default"].get<bool>());
    EXPECT_EQ(info["fields"][1]["association"], "cell");
    EXPECT_NEAR(info["fields"][1]["range"][1].get<double>(), 315.0, 1e-3);
    EXPECT_EQ(info["state"]["size"], nlohmann::json({64, 48}));
    EXPECT_EQ(info["state"]["tf"]["name"], "Viridis (matplotlib)");
    EXPECT_EQ(info["histogram"]["counts"].size(), 256u);
    EXPECT_GT(info["presets"].size(), 20u);
    const nlohmann::json f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_TRUE(f["full"].get<bool>());
    EXPECT_EQ(f["format"], "png");
    EXPECT_EQ(f["width"], 64);
    EXPECT_GT(f["stats"]["mean_samples_per_pixel"].get<double>(), 0.0);
    EXPECT_EQ(f["stats"]["device"], "cpu");
    EXPECT_TRUE(isPng(c.lastBinary()));
    // The scene came unprepared: the server prepared it at start, and the tab knows the result
    // from info or, when it connected during the preparation, from `prepared`.
    nlohmann::json cells = info["rendered_cells"];
    if (cells.is_null()) {
        bool seen = false;
        for (const nlohmann::json& j : c.seen())
            if (j.value("type", "") == "prepared") cells = j["rendered_cells"], seen = true;
        EXPECT_TRUE(seen) << "no prepared message";
    }
    EXPECT_EQ(cells, "216 cells (216 hexahedra)");  // native, not 1296 tetrahedra
}

TEST(ViewServer, APreparedSceneServesItsOneFieldWithTheMethodsItHolds) {
    // As `uvr view` serves a prepared cache: no mesh, a renderer prepared for the cell field g
    // with the partitions alone.
    const std::shared_ptr<Mesh> mesh = twoFieldMesh();
    RendererOptions ro;
    ro.device = Device::Cpu;
    ro.leafCells = 64;
    ro.partitions = true;
    ro.meshBvh = false;
    ViewScene scene;
    scene.file = "grid.vtk";
    scene.bounds = mesh->bounds();
    scene.renderer =
        std::make_unique<Renderer>(*mesh, selectScalarField(*mesh, parseFieldSpec("g")), ro);
    SourceSummary summary;
    summary.points = mesh->pointCount();
    summary.cells = mesh->cellCount();
    summary.bounds = mesh->bounds();
    summary.fieldName = "g";
    summary.association = Association::Cell;
    scene.fromCache = ViewScene::FromCache{"grid.vtk.uvrprep", "g:cell", summary};
    ViewState& s = scene.initial;
    s.camera = resetCamera(scene.bounds, 64.f / 48.f);
    s.tf = transferFunctionPreset("viridis");
    s.range = {100.f, 315.f};
    s.width = 64;
    s.height = 48;
    s.field = "g";
    ServerOptions o;
    o.port = 0;
    ViewServer server(std::move(scene), o);
    server.start();
    Client c(server.port(), server.token());
    const nlohmann::json info = c.next();
    ASSERT_EQ(info["type"], "info") << info.dump();
    EXPECT_EQ(info["cells"], 216);
    ASSERT_EQ(info["fields"].size(), 1u);
    EXPECT_EQ(info["fields"][0]["name"], "g");
    EXPECT_EQ(info["fields"][0]["association"], "cell");
    EXPECT_EQ(info["fields"][0]["range"], nlohmann::json({100.0, 315.0}));
    EXPECT_EQ(info["cell_types"], nlohmann::json({{"hexahedron", 216}}));
    EXPECT_EQ(info["methods"], nlohmann::json({"auto", "adaptive"}));
    for (const nlohmann::json& d : info["settings"])
        if (d["name"] == "method") {
            EXPECT_EQ(d["choices"], nlohmann::json({"auto", "adaptive"}));
        }
    std::uint64_t counted = 0;
    for (const nlohmann::json& n : info["histogram"]["counts"]) counted += n.get<std::uint64_t>();
    EXPECT_EQ(counted, 216u);  // one value per cell
    const nlohmann::json f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_TRUE(isPng(c.lastBinary()));
    EXPECT_GT(f["stats"]["samples"].get<double>(), 0.0);
    // Another field is not there; a method whose structures were not prepared is refused.
    c.send({{"type", "set"}, {"field", "f"}});
    EXPECT_THAT(c.until("error")["message"].get<std::string>(), HasSubstr("f"));
    c.send({{"type", "set"}, {"seq", 5}, {"method", "reference"}});
    EXPECT_THAT(c.until("error")["message"].get<std::string>(), HasSubstr("mesh BVH"));
    // The exported command names the field the cache was prepared for.
    c.send({{"type", "export"}});
    const nlohmann::json ex = c.until("export");
    ASSERT_FALSE(ex.is_null());
    EXPECT_THAT(ex["command"].get<std::string>(), HasSubstr("uvr render grid.vtk --field g:cell"));
}

TEST(ViewServer, RanksHoldingPartsListTheWholeMeshAndSwitchFields) {
    // `uvr view` under mpirun reads by parts (ViewScene::part): two in-process ranks, each with
    // half the cells of the two-field mesh; rank 0 serves, rank 1 follows. The page sees the
    // whole mesh's counts, ranges and histograms, and a field change reaches both parts.
    const std::shared_ptr<Mesh> whole = twoFieldMesh();
    const std::uint64_t n = whole->cellCount();
    std::uint64_t histogramCells = 0;
    std::atomic<std::uint64_t> partPoints{0};
    nlohmann::json info, g, gFrame;
    InProcessGroup::run(2, [&](Communicator& comm) {
        const int me = comm.rank();
        MeshShare share = shareOfPart(comm, meshPart(*whole, me * n / 2, (me + 1) * n / 2),
                                      parseFieldSpec(""), /*keepFields=*/true);
        partPoints += share.mesh.pointCount();
        ViewScene scene;
        scene.file = "grid.vtk";
        scene.bounds = whole->bounds();
        scene.part =
            ViewScene::Part{share.pointIds, share.cellIds, whole->pointCount(), n, std::nullopt};
        scene.mesh = std::make_shared<Mesh>(std::move(share.mesh));
        useTestFrames(scene);
        scene.rendererOptions.communicator = &comm;
        ServerOptions o;
        o.port = 0;
        ViewServer server(std::move(scene), o);
        if (me != 0) {
            server.follow();
            return;
        }
        server.start();
        {
            Client c(server.port(), server.token());
            info = c.next();
            ASSERT_FALSE(c.frame().is_null());
            c.send({{"type", "set"}, {"seq", 2}, {"field", "g"}});
            g = c.until("histogram");
            gFrame = c.frame();
        }
        server.stop();
    });
    ASSERT_EQ(info["type"], "info") << info.dump();
    EXPECT_EQ(info["cells"], 216);
    EXPECT_EQ(info["cell_types"], nlohmann::json({{"hexahedron", 216}}));
    ASSERT_EQ(info["fields"].size(), 2u);
    // f = x + 2y over [-1, 1]^3 (jittered corners inside), g = 100 + cell: both ranks' values.
    EXPECT_NEAR(info["fields"][1]["range"][0].get<double>(), 100.0, 1e-3);
    EXPECT_NEAR(info["fields"][1]["range"][1].get<double>(), 315.0, 1e-3);
    const auto range = finiteRange(scalarFieldOf(*whole, whole->fields[0]).values);
    EXPECT_FLOAT_EQ(info["fields"][0]["range"][0].get<float>(), range.first);
    EXPECT_FLOAT_EQ(info["fields"][0]["range"][1].get<float>(), range.second);
    // Every part's points: those on the faces the parts share count once for each.
    for (const nlohmann::json& c : info["histogram"]["counts"])
        histogramCells += c.get<std::uint64_t>();
    EXPECT_EQ(histogramCells, partPoints);
    ASSERT_FALSE(g.is_null());
    EXPECT_EQ(g["field"], "g");
    std::uint64_t gCells = 0;
    for (const nlohmann::json& c : g["counts"]) gCells += c.get<std::uint64_t>();
    EXPECT_EQ(gCells, 216u);  // one value per cell, over both parts
    ASSERT_FALSE(gFrame.is_null());
    EXPECT_EQ(gFrame["seq"], 2);
}

#ifdef UVR_HAVE_NETCDF
TEST(ViewServer, RanksHoldingPartsOfASeriesShowItsSteps) {
    // `uvr view` under mpirun on a series stored in parts (an Exodus II file: its cells): each
    // of two in-process ranks reads its run of each step's cells, and a step change reaches
    // both parts: the page sees the whole step's range, and the frame is one process's.
    if (!exodusSupported()) GTEST_SKIP() << "built without netCDF";
    const Mesh grid = testing::makeHexGrid(
        6, -1.f, 1.f, [](Vec3f p) { return p.x; }, 0.2f);
    const std::string file = testing::scratchDir() + "/series.exo";
    testing::writeExodusFile(file,
                             testing::hexSeriesSpec(grid, 3, [&](std::size_t s, std::size_t n) {
                                 const Vec3f p = grid.points[n];
                                 return double(p.x + 2.f * p.y * std::cos(float(s)));
                             }));
    const auto sceneOf = [&](std::shared_ptr<MeshSeries> series, Communicator* comm) {
        ViewScene scene;
        scene.file = file;
        if (comm) {
            const auto run = rankRun(series->partCount(0), comm->rank(), comm->size());
            MeshShare share = shareOfPart(*comm, series->readPart(0, run.first, run.second),
                                          parseFieldSpec(""), /*keepFields=*/true);
            scene.part = ViewScene::Part{share.pointIds, share.cellIds, grid.pointCount(),
                                         grid.cellCount(), run};
            scene.mesh = std::make_shared<Mesh>(std::move(share.mesh));
            scene.rendererOptions.communicator = comm;
        } else {
            scene.mesh = std::make_shared<Mesh>(series->readStep(0));
        }
        scene.series = std::move(series);
        scene.bounds = grid.bounds();
        useTestFrames(scene);
        return scene;
    };
    // What the page gets at step 2: the histogram's range and the frame.
    const auto step2 = [](ViewServer& server, nlohmann::json& histogram, std::string& frame) {
        server.start();
        {
            Client c(server.port(), server.token());
            ASSERT_FALSE(c.frame().is_null());
            c.send({{"type", "set"}, {"seq", 2}, {"step", 2}});
            histogram = c.until("histogram");
            const nlohmann::json f = c.frame();
            ASSERT_FALSE(f.is_null());
            EXPECT_EQ(f["seq"], 2);
            frame = c.lastBinary();
        }
        server.stop();
    };
    nlohmann::json oneHistogram, histogram;
    std::string oneFrame, frame;
    {
        ServerOptions o;
        o.port = 0;
        ViewServer one(sceneOf(openMeshSeries(file), nullptr), o);
        step2(one, oneHistogram, oneFrame);
    }
    std::vector<std::uint64_t> cells(2);
    InProcessGroup::run(2, [&](Communicator& comm) {
        ViewScene scene = sceneOf(openMeshSeries(file), &comm);
        cells[comm.rank()] = scene.mesh->cellCount();
        ServerOptions o;
        o.port = 0;
        ViewServer server(std::move(scene), o);
        if (comm.rank() != 0) {
            server.follow();
            return;
        }
        step2(server, histogram, frame);
    });
    EXPECT_EQ(cells[0] + cells[1], grid.cellCount());  // each rank read half the cells
    ASSERT_FALSE(histogram.is_null());
    ASSERT_FALSE(oneHistogram.is_null());
    EXPECT_EQ(histogram["range"], oneHistogram["range"]);
    const std::string dir = testing::scratchDir();
    const Image a = readPng(testing::writeFile(dir + "/one.png", oneFrame));
    const Image b = readPng(testing::writeFile(dir + "/two.png", frame));
    const ImageComparison cmp = compareImages(toRgb8(a), toRgb8(b));
    EXPECT_GE(cmp.ssim, 0.999);
    EXPECT_LE(cmp.maxAbsDifference, 2.0) << differenceSummary(cmp);
}
#endif

TEST(ViewServer, MovingFramesAreReducedJpegsAndStillOnesRefineToFullPngs) {
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    nlohmann::json cam = c.seen().front()["state"]["camera"];
    cam["position"][0] = 4.0;
    c.send({{"type", "set"}, {"seq", 5}, {"interactive", true}, {"camera", cam}});
    const nlohmann::json moving = c.frame();
    ASSERT_FALSE(moving.is_null());
    EXPECT_EQ(moving["seq"], 5);
    EXPECT_FALSE(moving["full"].get<bool>());
    EXPECT_EQ(moving["format"], "jpeg");
    EXPECT_TRUE(isJpeg(c.lastBinary()));
    EXPECT_GE(moving["scale"].get<int>(), 1);
    EXPECT_EQ(moving["width"].get<int>(), 64 / moving["scale"].get<int>());
    // No further change: the refinement comes by itself.
    const nlohmann::json still = c.frame();
    ASSERT_FALSE(still.is_null());
    EXPECT_EQ(still["seq"], 5);
    EXPECT_TRUE(still["full"].get<bool>());
    EXPECT_EQ(still["width"], 64);
    EXPECT_TRUE(isPng(c.lastBinary()));
    const std::string before = c.lastBinary();
    // A TF change alone gives a different image.
    c.send({{"type", "set"}, {"seq", 6}, {"tf", {{"opacity", {{0, 0.9}, {1, 0.9}}}}}});
    const nlohmann::json tf = c.frame();
    ASSERT_FALSE(tf.is_null());
    EXPECT_EQ(tf["seq"], 6);
    EXPECT_NE(c.lastBinary(), before);
}

TEST(ViewServer, WrongTokensGetNoPageAndNoSocket) {
    auto server = startServer();
    const std::uint16_t port = server->port();
    EXPECT_THROW(Client(port, "0123456789abcdef0123456789abcdef"), beast::system_error);
    EXPECT_THROW(Client(port, ""), beast::system_error);
    EXPECT_EQ(httpGet(port, "/?token=wrong"), 403);
    EXPECT_EQ(httpGet(port, "/"), 403);
    EXPECT_EQ(httpGet(port, "/app.js"), 403);
    EXPECT_EQ(httpGet(port, "/no-such-file.js?token=" + server->token()), 404);
    if (!findWebAsset("index.html")) GTEST_SKIP() << "the page (web/) is not built in";
    std::string cookie, body;
    EXPECT_EQ(httpGet(port, "/?token=" + server->token(), "", &cookie, &body), 200);
    EXPECT_THAT(body, HasSubstr("<html"));
    EXPECT_THAT(cookie, HasSubstr("HttpOnly"));
    const std::string pair = cookie.substr(0, cookie.find(';'));
    EXPECT_EQ(pair, "uvr_token_" + std::to_string(port) + "=" + server->token());
    // The page's files come with the cookie, not without it or with another one.
    const std::string other = pair.substr(0, pair.find('=') + 1) + "x";
    for (std::string name : {"app.js", "style.css"}) {
        if (!findWebAsset(name)) continue;
        EXPECT_EQ(httpGet(port, "/" + name, pair), 200) << name;
        EXPECT_EQ(httpGet(port, "/" + name), 403) << name;
        EXPECT_EQ(httpGet(port, "/" + name, other), 403) << name;
    }
}

TEST(ViewServer, BadMessagesGetErrorsAndTheConnectionKeepsServing) {
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"{not json", "malformed JSON"},
        {"[1, 2]", "\"type\""},
        {R"({"type": 7})", "\"type\""},
        {R"({"type": "launch"})", "unknown message type \"launch\""},
        {R"({"type": "set", "quality": 7})", "\"quality\""},
        {R"({"type": "set", "seq": -1, "heatmap": true})", "\"seq\""},
        {R"({"type": "set", "field": "nope"})", "nope"},
        {R"({"type": "set", "interactive": "yes"})", "interactive"},
        {R"({"type": "reset_camera", "axis": "+w"})", "axis"},
    };
    for (const auto& [text, want] : cases) {
        c.sendText(text);
        const nlohmann::json e = c.until("error");
        ASSERT_FALSE(e.is_null()) << text;
        EXPECT_THAT(e["message"].get<std::string>(), HasSubstr(want)) << text;
    }
    // A refused change names its seq and is followed by the state as it stays.
    c.send({{"type", "set"}, {"seq", 77}, {"quality", 2}});
    const nlohmann::json e77 = c.until("error");
    ASSERT_FALSE(e77.is_null());
    EXPECT_EQ(e77["seq"], 77);
    EXPECT_EQ(e77["request"], "set");
    const nlohmann::json kept = c.until("state");
    ASSERT_FALSE(kept.is_null());
    EXPECT_NEAR(kept["state"]["quality"].get<double>(), 0.99, 1e-6);
    c.sendBinary(std::string("\x89PNG", 4));
    EXPECT_THAT(c.until("error")["message"].get<std::string>(), HasSubstr("binary"));
    // The bad seq and heat map above changed nothing: the state still shows the volume.
    c.send({{"type", "ping"}, {"seq", 3}});
    const nlohmann::json pong = c.until("pong");
    ASSERT_FALSE(pong.is_null());
    EXPECT_EQ(pong["seq"], 3);
    c.send({{"type", "set"}, {"seq", 9}, {"method", "exact"}});
    const nlohmann::json f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_EQ(f["seq"], 9);
    EXPECT_EQ(f["stats"]["method"], "exact");
}

TEST(ViewServer, AFloodIsLimitedAndNeverQueuesFrames) {
    ServerOptions o;
    o.maxMessagesPerSecond = 100;
    auto server = startServer(o);
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    nlohmann::json cam = c.seen().front()["state"]["camera"];
    for (int i = 1; i <= 2000; ++i) {
        cam["position"][0] = 3.0 + i * 1e-3;
        c.send({{"type", "set"}, {"seq", i}, {"interactive", true}, {"camera", cam}});
    }
    // Read everything the flood produced until the connection goes quiet.
    int frames = 0, errors = 0;
    std::uint64_t lastSeq = 0;
    for (nlohmann::json j = c.next(1500ms); !j.is_null(); j = c.next(1500ms)) {
        if (j.value("type", "") == "frame") ++frames, lastSeq = j["seq"];
        if (j.value("type", "") == "error") {
            ++errors;
            EXPECT_THAT(j["message"].get<std::string>(), HasSubstr("too many messages"));
        }
    }
    EXPECT_FALSE(c.closed());
    EXPECT_GE(errors, 1);
    EXPECT_LT(frames, 100) << "frames were queued, not replaced";
    EXPECT_GE(lastSeq, 100u);   // the burst's newest accepted state was shown
    EXPECT_LT(lastSeq, 2000u);  // later ones were dropped
    // Once the flood is over the connection is heard again.
    std::this_thread::sleep_for(1100ms);
    c.send({{"type", "set"}, {"seq", 5000}, {"camera", cam}});
    const nlohmann::json f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_EQ(f["seq"], 5000);
}

TEST(ViewServer, SnapshotAndExportReproduceTheState) {
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    c.send({{"type", "set"}, {"preset", "Inferno (matplotlib)"}, {"range", {-2.5, 2.5}}});
    const nlohmann::json state = c.until("state");
    ASSERT_FALSE(state.is_null());
    EXPECT_EQ(state["state"]["tf"]["name"], "Inferno (matplotlib)");
    c.send({{"type", "snapshot"}});
    const nlohmann::json snap = c.until("snapshot");
    ASSERT_FALSE(snap.is_null());
    EXPECT_EQ(snap["width"], 64);
    EXPECT_EQ(snap["height"], 48);
    EXPECT_TRUE(c.next().contains("binary"));
    EXPECT_TRUE(isPng(c.lastBinary()));
    // Composited over the page's background, as the frames are (IHDR colour type 2: RGB).
    ASSERT_GT(c.lastBinary().size(), 25u);
    EXPECT_EQ(static_cast<unsigned char>(c.lastBinary()[25]), 2u);
    c.send({{"type", "export"}});
    const nlohmann::json ex = c.until("export");
    ASSERT_FALSE(ex.is_null());
    const std::string tfText = ex["tf_json"], pvcc = ex["pvcc"];
    const TransferFunction tf = parseParaViewColorMap({tfText.begin(), tfText.end()}, "export");
    EXPECT_EQ(tf.name, "Inferno (matplotlib)");
    EXPECT_FLOAT_EQ(tf.sourceRange->first, -2.5f);
    const Camera cam = parsePvcc({pvcc.begin(), pvcc.end()}, "export");
    EXPECT_NEAR(cam.position.z, state["state"]["camera"]["position"][2].get<double>(), 1e-4);
    const std::string cmd = ex["command"];
    EXPECT_THAT(cmd, HasSubstr("uvr render grid.vtk --tf uvr-tf.json --camera uvr-camera.pvcc "
                               "--range -2.5,2.5 --size 64x48 --method auto --opacity-unit 0.5 "
                               "--sample-distance 0.01 --background 0,0,0 -o uvr-view.png"));
    // The adaptive method exports its quality; so does auto with a quality of its own (which
    // makes its frames adaptive).
    // The page's clip planes export as flags.
    c.send({{"type", "set"}, {"clip_planes", {{0.25, 0, 0, 1, 0, 0}}}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(),
                HasSubstr("--clip-plane 0.25,0,0,1,0,0 --sample-distance 0.01"));
    c.send({{"type", "set"}, {"clip_planes", nlohmann::json::array()}});
    // So do its isosurfaces.
    c.send({{"type", "set"}, {"iso", {"0.5", "1,0.5,#00ff00"}}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(),
                HasSubstr("--iso 0.5 --iso '1,0.5,#00ff00' --sample-distance 0.01"));
    c.send({{"type", "set"}, {"iso", nlohmann::json::array()}});
    // So does its gradient opacity, with the normals it reads.
    c.send({{"type", "set"}, {"gradient_opacity", "0:0,2:1"}, {"normals", "cell"}});
    c.send({{"type", "export"}});
    {
        const std::string gop = c.until("export")["command"].get<std::string>();
        EXPECT_THAT(gop, HasSubstr("--normals cell"));
        EXPECT_THAT(gop, HasSubstr("--gradient-opacity 0:0,2:1 --sample-distance 0.01"));
    }
    c.send({{"type", "set"}, {"gradient_opacity", ""}, {"normals", "smooth"}});
    // The cut face exports with a clip plane, and not without one (the CLI refuses it then).
    c.send({{"type", "set"}, {"clip_surface", true}, {"clip_planes", {{0.25, 0, 0, 1, 0, 0}}}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(), HasSubstr("--clip-surface"));
    c.send({{"type", "set"}, {"clip_planes", nlohmann::json::array()}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(), Not(HasSubstr("--clip-surface")));
    c.send({{"type", "set"}, {"clip_surface", false}});
    c.send({{"type", "set"}, {"method", "adaptive"}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(),
                HasSubstr("--method adaptive --quality 0.99 --opacity-unit"));
    c.send({{"type", "set"}, {"method", "auto"}, {"quality", 0.995}});
    c.send({{"type", "export"}});
    EXPECT_THAT(c.until("export")["command"].get<std::string>(),
                HasSubstr("--method auto --quality 0.995 --opacity-unit"));
    c.send({{"type", "set"}, {"quality", 0.99}});
    // A log scale over a range from 0 exports the range the frames map (AdjustRangeForLog).
    c.send({{"type", "set"}, {"range", {0, 2}}, {"tf", {{"log", true}}}});
    c.send({{"type", "export"}});
    const nlohmann::json logEx = c.until("export");
    ASSERT_FALSE(logEx.is_null());
    EXPECT_THAT(logEx["command"].get<std::string>(), HasSubstr("--range 0.0002,2 "));
    // The log state's frame may come before the export's reply (until() keeps what it skips) or
    // after it, and a frame of the state before may come first.
    auto saysNotPositive = [](const nlohmann::json& f) {
        return f.value("type", "") == "frame" && f.contains("notes") && !f["notes"].empty() &&
               f["notes"][0].get<std::string>().find("not positive") != std::string::npos;
    };
    bool noted = false;
    for (const nlohmann::json& j : c.seen()) noted = noted || saysNotPositive(j);
    for (int i = 0; i < 4 && !noted; ++i) {
        const nlohmann::json f = c.frame();
        if (f.is_null()) break;
        noted = saysNotPositive(f);
    }
    EXPECT_TRUE(noted) << "no frame noted that the log range's lower end is not positive";
}

TEST(ViewServer, AFieldChangeSendsItsRangeAndHistogramAndRebuildsNoGeometry) {
    std::mutex mu;
    std::vector<std::string> log;
    auto server = startServer({}, [&](const std::string& line) {
        std::lock_guard lk(mu);
        log.push_back(line);
    });
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    const std::string first = c.lastBinary();
    c.send({{"type", "set"}, {"seq", 2}, {"field", "g"}});
    const nlohmann::json h = c.until("histogram");
    ASSERT_FALSE(h.is_null());
    EXPECT_EQ(h["field"], "g");
    const nlohmann::json st = c.until("state");
    ASSERT_FALSE(st.is_null());
    EXPECT_EQ(st["state"]["range"], nlohmann::json({100.0, 315.0}));
    const nlohmann::json f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_EQ(f["seq"], 2);
    EXPECT_NE(c.lastBinary(), first);
    // Back to f with its first range: the very first image again.
    c.send({{"type", "set"}, {"seq", 3}, {"field", "f"}, {"range", {-3, 3}}});
    const nlohmann::json back = c.until("histogram");
    ASSERT_FALSE(back.is_null());
    EXPECT_EQ(back["field"], "f");
    const nlohmann::json g = c.frame();
    ASSERT_FALSE(g.is_null());
    EXPECT_EQ(g["seq"], 3);
    EXPECT_EQ(c.lastBinary(), first);
    std::lock_guard lk(mu);
    int prepared = 0, switched = 0;
    for (const std::string& line : log) {
        prepared += line.find("prepared") != std::string::npos;
        switched += line.find("no geometry rebuilt") != std::string::npos;
    }
    EXPECT_EQ(prepared, 1);  // the first frame's; the scene came without a renderer
    EXPECT_EQ(switched, 2);
}

TEST(ViewServer, TimeStepsOfASeriesAreShownWithoutRebuildingAndOtherGeometriesRefused) {
    // Steps 0-2: the two-field mesh with f moved by the step; step 3: another grid.
    const std::string dir = uvr::testing::scratchDir();
    for (int k = 0; k < 3; ++k) {
        Mesh m = *twoFieldMesh();
        for (float& v : m.fields[0].values) v += float(k);
        writeMesh(m, dir + "/s_" + std::to_string(k) + ".vtu");
    }
    Mesh other = testing::makeHexGrid(4, -1.f, 1.f);
    other.fields.push_back({"g", Association::Cell, 1, std::vector<float>(64, 1.f)});
    writeMesh(other, dir + "/s_3.vtu");
    std::mutex mu;
    std::vector<std::string> log;
    ViewScene scene;
    scene.file = dir + "/s_*.vtu";
    scene.series = openMeshSeries(scene.file);
    scene.mesh = std::make_shared<Mesh>(scene.series->readStep(0));
    scene.bounds = scene.mesh->bounds();
    scene.rendererOptions.device = Device::Cpu;
    ViewState& st = scene.initial;
    st.camera = resetCamera(scene.bounds, 64.f / 48.f);
    st.tf = transferFunctionPreset("viridis");
    applyOpacitySpec(st.tf, "0:0,1:0.6");
    st.range = {-3.f, 5.f};
    st.width = 64;
    st.height = 48;
    ServerOptions o;
    o.port = 0;
    ViewServer server(std::move(scene), o, [&](const std::string& line) {
        std::lock_guard lk(mu);
        log.push_back(line);
    });
    server.start();
    Client c(server.port(), server.token());
    const nlohmann::json info = c.until("info");
    ASSERT_FALSE(info.is_null());
    EXPECT_EQ(info["times"], nlohmann::json({0, 1, 2, 3}));
    EXPECT_EQ(info["state"]["step"], 0);
    ASSERT_FALSE(c.frame().is_null());
    const std::string first = c.lastBinary();
    // Step 2: its histogram, the tab's range kept, a new image.
    c.send({{"type", "set"}, {"seq", 2}, {"step", 2}});
    const nlohmann::json h = c.until("histogram");
    ASSERT_FALSE(h.is_null());
    EXPECT_NEAR(h["range"][0].get<double>(), -3.0 + 2.0, 0.7);  // f moved by 2
    const nlohmann::json state = c.until("state");
    EXPECT_EQ(state["state"]["step"], 2);
    EXPECT_EQ(state["state"]["range"], nlohmann::json({-3.0, 5.0}));
    const nlohmann::json f2 = c.frame();
    ASSERT_FALSE(f2.is_null());
    EXPECT_EQ(f2["seq"], 2);
    EXPECT_NE(c.lastBinary(), first);
    c.send({{"type", "export"}});
    const nlohmann::json ex = c.until("export");
    ASSERT_FALSE(ex.is_null());
    EXPECT_THAT(ex["command"].get<std::string>(), HasSubstr("--step-index 2 "));
    // Out of range: refused by the state; another geometry: refused by the frame.
    c.send({{"type", "set"}, {"seq", 3}, {"step", 4}});
    nlohmann::json e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("from 0 to 3"));
    c.send({{"type", "set"}, {"seq", 4}, {"step", 3}});
    e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("other points or cells"));
    // Back to step 0: the first image again, and the server still serves.
    c.send({{"type", "set"}, {"seq", 5}, {"step", 0}});
    const nlohmann::json f0 = c.frame();
    ASSERT_FALSE(f0.is_null());
    EXPECT_EQ(f0["seq"], 5);
    EXPECT_EQ(c.lastBinary(), first);
    std::lock_guard lk(mu);
    int prepared = 0, steps = 0;
    for (const std::string& line : log) {
        prepared += line.find("prepared") != std::string::npos;
        steps += line.find("read time step") != std::string::npos;
    }
    EXPECT_EQ(prepared, 1);
    EXPECT_EQ(steps, 2);  // step 2, then step 0 again
}

TEST(ViewServer, TabsHaveTheirOwnStateAndResetCameraSnapsToAxes) {
    auto server = startServer();
    Client a(server->port(), server->token()), b(server->port(), server->token());
    ASSERT_FALSE(a.frame().is_null());
    ASSERT_FALSE(b.frame().is_null());
    a.send({{"type", "reset_camera"}, {"seq", 1}, {"axis", "+x"}});
    const nlohmann::json st = a.until("state");
    ASSERT_FALSE(st.is_null());
    const nlohmann::json cam = st["state"]["camera"];
    EXPECT_LT(cam["position"][0].get<double>(), -1.0);  // looking along +x from -x
    EXPECT_EQ(cam["view_up"], nlohmann::json({0.0, 0.0, 1.0}));
    ASSERT_FALSE(a.frame().is_null());
    b.send({{"type", "export"}});
    const std::string pvcc = b.until("export")["pvcc"];
    const Camera bCam = parsePvcc({pvcc.begin(), pvcc.end()}, "b");
    EXPECT_EQ(bCam.viewUp, Vec3f(0.f, 1.f, 0.f));  // b still has the starting camera
}

TEST(ViewServer, OversizedMessagesCloseTheConnectionAndLimitsCapSessions) {
    ServerOptions o;
    o.maxMessageBytes = 1024;
    o.maxSessions = 1;
    auto server = startServer(o);
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    EXPECT_THROW(Client(server->port(), server->token()), beast::system_error);  // one only
    c.sendText(R"({"type": "set", "colormap_json": ")" + std::string(2000, 'x') + "\"}");
    EXPECT_TRUE(c.until("never", 5s).is_null());
    EXPECT_TRUE(c.closed());
    // Its place is free again.
    std::this_thread::sleep_for(100ms);
    Client d(server->port(), server->token());
    EXPECT_EQ(d.next()["type"], "info");
}

TEST(ViewServer, StopClosesConnectionsAndBadOptionsAreRefused) {
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    std::thread runner([&] { server->run(false); });
    server->stop();
    runner.join();
    for (nlohmann::json j = c.next(3s); !j.is_null(); j = c.next(3s)) {
    }
    EXPECT_TRUE(c.closed()) << "no close from the server";
    auto refused = [](ServerOptions o) {
        ViewScene scene;
        scene.mesh = twoFieldMesh();
        scene.initial.field = "f";
        try {
            ViewServer s(std::move(scene), o);
        } catch (const Error& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    ServerOptions shortToken;
    shortToken.token = "abc";
    EXPECT_THAT(refused(shortToken), HasSubstr("`token`"));
    ServerOptions oddToken;
    oddToken.token = "0123456789abcdef;rm";
    EXPECT_THAT(refused(oddToken), HasSubstr("`token`"));
    ServerOptions badHost;
    badHost.host = "not-an-address";
    EXPECT_THAT(refused(badHost), HasSubstr("`host` not-an-address"));
    for (const double ms : {0.0, 4.9, 1001.0, double(NAN)}) {
        ServerOptions frameMs;
        frameMs.targetFrameMs = ms;
        EXPECT_THAT(refused(frameMs), HasSubstr("`moving_frame_ms`")) << ms;
    }
    // A port in use is found before any work, and by start.
    auto busy = startServer();
    ServerOptions same;
    same.port = busy->port();
    try {
        checkServerOptions(same, true);
        ADD_FAILURE() << "a busy port passed";
    } catch (const Error& e) {
        EXPECT_EQ(e.kind(), ErrorKind::Io);
        EXPECT_THAT(e.what(), HasSubstr("cannot listen on 127.0.0.1:" + std::to_string(same.port)));
    }
    EXPECT_NO_THROW(checkServerOptions(ServerOptions{}, false));
    ServerOptions named;
    named.host = "localhost";  // the one name taken: 127.0.0.1
    EXPECT_NO_THROW(checkServerOptions(named, false));
}

/// Log lines of a server, kept for a test to count.
struct LogLines {
    std::mutex mu;
    std::vector<std::string> lines;
    LogFn fn() {
        return [this](const std::string& line) {
            std::lock_guard lk(mu);
            lines.push_back(line);
        };
    }
    int count(const std::string& part) {
        std::lock_guard lk(mu);
        int n = 0;
        for (const std::string& l : lines) n += l.find(part) != std::string::npos;
        return n;
    }
};

/// True when the server closes the socket (it reads end of file or an error) within timeout.
bool closedByServer(tcp::socket& socket, std::chrono::milliseconds timeout) {
    pollfd p{socket.native_handle(), POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return false;
    char byte;
    return ::recv(socket.native_handle(), &byte, 1, MSG_DONTWAIT) <= 0;
}

/// CPU seconds (user + system) this process has used.
double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Resident memory of this process in bytes (VmRSS of /proc/self/status; 0 when unknown).
std::size_t residentBytes() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
    return 0;
}

/// A ParaView colour-map JSON of n RGB points.
std::string colorMapJson(std::size_t n) {
    nlohmann::json rgb = nlohmann::json::array();
    for (std::size_t i = 0; i < n; ++i)
        for (double v : {double(i), 0.25, 0.5, 0.75}) rgb.push_back(v);
    return nlohmann::json::array({{{"Name", "many"}, {"ColorSpace", "RGB"}, {"RGBPoints", rgb}}})
        .dump();
}

TEST(ViewServer, DeeplyNestedMessagesAreRefusedBeforeParsing) {
    // Issue 28: 100,000 levels killed the server (stack overflow copying and dumping the value
    // to describe it in the error).
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    const std::string deep = R"({"type":"set","seq":4,"range":[)" + std::string(99999, '[') +
                             std::string(99999, ']') + ",1]}";
    c.sendText(deep);
    nlohmann::json e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("nested deeper than 64 levels"));
    // At the limit it parses, and the error describes the value in a few bytes.
    c.sendText(R"({"type":"set","seq":5,"range":[)" + std::string(58, '[') + std::string(58, ']') +
               ",1]}");  // 60 levels with the object and the range
    e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_EQ(e["seq"], 5);
    EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("\"range[0]\""));
    // A huge token in malformed JSON, or a huge seq, comes back cut, never whole.
    c.sendText(R"({"type":"set","range":")" + std::string(1 << 20, 'z') + "\\q\"}");
    e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_LE(e["message"].get<std::string>().size(), 512u);
    c.send({{"type", "ping"}, {"seq", std::string(1 << 20, 's')}});
    e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_FALSE(e.contains("seq"));
    EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("\"seq\""));
    c.send({{"type", "ping"}, {"seq", 8}});
    EXPECT_EQ(c.until("pong")["seq"], 8);
}

TEST(ViewServer, RepliesToATabThatDoesNotReadAreReplacedNotQueued) {
    // Issue 28: every `export` reply carried the whole (250,000-point) map and up to 256 of
    // them waited per connection. Now the newest reply replaces one still waiting.
    auto server = startServer();
    Client c(server->port(), server->token());
    ASSERT_FALSE(c.frame().is_null());
    c.send({{"type", "set"}, {"colormap_json", colorMapJson(kMaxTfPoints)}});
    const nlohmann::json st = c.until("state");
    ASSERT_FALSE(st.is_null());
    ASSERT_EQ(st["state"]["tf"]["colors"].size(), kMaxTfPoints);
    const int requests = 150;  // 40 MB of replies; within the rate and the message count
    for (int i = 0; i < requests; ++i) c.send({{"type", "export"}});
    std::this_thread::sleep_for(1500ms);
    // The first reply may take long where the server is slow (sanitizer builds); then the rest.
    int exports = c.until("export", 60s).is_null() ? 0 : 1;
    for (nlohmann::json j = c.next(1500ms); !j.is_null(); j = c.next(1500ms))
        exports += j.value("type", "") == "export";
    EXPECT_FALSE(c.closed());
    EXPECT_GE(exports, 1);
    EXPECT_LT(exports, requests / 2) << "replies were queued, not replaced";
    // A map past the limit is refused, the connection serves on.
    c.send({{"type", "set"}, {"seq", 3}, {"colormap_json", colorMapJson(kMaxTfPoints + 1)}});
    const nlohmann::json e = c.until("error");
    ASSERT_FALSE(e.is_null());
    EXPECT_THAT(e["message"].get<std::string>(),
                HasSubstr("at most " + std::to_string(kMaxTfPoints)));
    c.send({{"type", "ping"}, {"seq", 1}});
    EXPECT_FALSE(c.until("pong").is_null());
}

TEST(ViewServer, ATabWhoseQueuedBytesPassTheBoundIsClosed) {
    // Replies that replace nothing (errors) pile up for a tab that never reads: past
    // maxQueuedBytes (fewer than the 256 messages of the count) the connection is closed.
    LogLines log;
    ServerOptions o;
    o.maxQueuedBytes = 16 << 10;
    o.maxMessagesPerSecond = 100000;
    auto server = startServer(o, log.fn());
    Client c(server->port(), server->token(), 4096);
    ASSERT_FALSE(c.frame().is_null());
    // Malformed JSON quoting a long token: errors of ~600 bytes (cut at 512 for the message).
    const std::string bad = R"({"type":"set","range":")" + std::string(2000, 'r') + "\\q\"}";
    // ~9 MB of errors: more than the kernel's buffers of the socket (4 MiB at most) hold.
    try {
        for (int i = 0; i < 16000; ++i) c.sendText(bad);
    } catch (const beast::system_error&) {
        // closed while sending
    }
    for (int i = 0; i < 50 && !log.count("does not read"); ++i) std::this_thread::sleep_for(100ms);
    ASSERT_EQ(log.count("does not read"), 1);
    // Closed for its bytes, with fewer messages waiting than the count allows.
    std::string line;
    {
        std::lock_guard lk(log.mu);
        for (const std::string& l : log.lines)
            if (l.find("does not read") != std::string::npos) line = l;
    }
    const auto open = line.find(" (");
    ASSERT_NE(open, std::string::npos) << line;
    EXPECT_LT(std::stoi(line.substr(open + 2)), 256) << line;
    EXPECT_THAT(line, HasSubstr("bytes of text"));
    for (nlohmann::json j = c.next(3s); !j.is_null(); j = c.next(3s)) {
    }
    EXPECT_TRUE(c.closed());
    Client d(server->port(), server->token());  // the server serves on
    EXPECT_FALSE(d.frame().is_null());
}

TEST(ViewServer, ConnectionsAreCappedAndIdleOnesWithoutATokenTimeOut) {
    // Issue 28: nothing bounded the connections without a token.
    ServerOptions o;
    o.maxConnections = 4;
    o.idleSeconds = 0.5;
    auto server = startServer(o);
    net::io_context ioc;
    const tcp::endpoint to(net::ip::make_address("127.0.0.1"), server->port());
    std::vector<tcp::socket> idle;
    for (int i = 0; i < 12; ++i) {
        idle.emplace_back(ioc);
        idle.back().connect(to);
    }
    // The newest stay (up to the cap), the older ones made room; soon all time out.
    int closedSoon = 0;
    for (tcp::socket& s : idle) closedSoon += closedByServer(s, 200ms);
    EXPECT_GE(closedSoon, 12 - 4);
    for (tcp::socket& s : idle) EXPECT_TRUE(closedByServer(s, 5s));
    // A tab still gets in, and an idle connection does not shut it out.
    tcp::socket one(ioc);
    one.connect(to);
    Client c(server->port(), server->token());
    EXPECT_FALSE(c.frame().is_null());
}

TEST(ViewServer, AcceptBacksOffWhenNoDescriptorIsLeft) {
    // Issue 28: under `ulimit -n 64`, accept failed with EMFILE and was retried at once
    // forever: 100% CPU and megabytes of log lines a second.
    LogLines log;
    auto server = startServer({}, log.fn());
    {
        // One frame first, so that the renderer's thread pools (libomp opens a shared-memory
        // file when it starts, and exits the process if it cannot) exist before the
        // descriptors run out.
        Client warm(server->port(), server->token());
        ASSERT_FALSE(warm.frame().is_null());
    }
    net::io_context ioc;
    std::vector<tcp::socket> clients;
    for (int i = 0; i < 20; ++i) {
        clients.emplace_back(ioc);
        clients.back().open(tcp::v4());  // their descriptors before the others run out
    }
    rlimit old{};
    ASSERT_EQ(getrlimit(RLIMIT_NOFILE, &old), 0);
    rlimit low = old;
    low.rlim_cur = std::min<rlim_t>(old.rlim_cur, 1024);
    ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &low), 0);
    std::vector<int> used;
    const int null = ::open("/dev/null", O_RDONLY);
    ASSERT_GE(null, 0);
    used.push_back(null);
    for (int fd = ::dup(null); fd >= 0; fd = ::dup(null)) used.push_back(fd);
    const tcp::endpoint to(net::ip::make_address("127.0.0.1"), server->port());
    for (tcp::socket& s : clients) s.connect(to);  // queued by the kernel; accept fails
    const double cpu0 = cpuSeconds();
    std::this_thread::sleep_for(2s);
    const double cpu = cpuSeconds() - cpu0;
    for (int fd : used) ::close(fd);
    setrlimit(RLIMIT_NOFILE, &old);
    EXPECT_GE(log.count("accept failed"), 1);
    EXPECT_LE(log.count("accept failed"), 2) << "accept errors are not rate-limited";
    EXPECT_LT(cpu, 0.5) << "accept is retried without a pause";
    // Descriptors free again: the queued connections and a new tab are served.
    Client c(server->port(), server->token());
    EXPECT_FALSE(c.frame().is_null());
}

TEST(ViewServer, AStepThatFailsToReadIsAnErrorForThatTabOnly) {
    // Issue 28: a failure while loading a tab's time step (a truncated file here, a .pvd
    // cycle or bad_alloc there) must not take the server down.
    const std::string dir = uvr::testing::scratchDir();
    for (int k = 0; k < 3; ++k) {
        Mesh m = *twoFieldMesh();
        for (float& v : m.fields[0].values) v += float(k);
        writeMesh(m, dir + "/s_" + std::to_string(k) + ".vtu");
    }
    ViewScene scene;
    scene.file = dir + "/s_*.vtu";
    scene.series = openMeshSeries(scene.file);
    scene.mesh = std::make_shared<Mesh>(scene.series->readStep(0));
    scene.bounds = scene.mesh->bounds();
    scene.rendererOptions.device = Device::Cpu;
    ViewState& st = scene.initial;
    st.camera = resetCamera(scene.bounds, 64.f / 48.f);
    st.tf = transferFunctionPreset("viridis");
    st.range = {-3.f, 5.f};
    st.width = 64;
    st.height = 48;
    // Step 2 is cut short after the series was opened.
    const std::string step2 = dir + "/s_2.vtu";
    std::filesystem::resize_file(step2, std::filesystem::file_size(step2) / 2);
    ServerOptions o;
    o.port = 0;
    ViewServer server(std::move(scene), o);
    server.start();
    Client a(server.port(), server.token()), b(server.port(), server.token());
    ASSERT_FALSE(a.frame().is_null());
    ASSERT_FALSE(b.frame().is_null());
    for (int attempt = 0; attempt < 2; ++attempt) {
        a.send({{"type", "set"}, {"seq", 10 + attempt}, {"step", 2}});
        const nlohmann::json e = a.until("error");
        ASSERT_FALSE(e.is_null());
        EXPECT_EQ(e["request"], "frame");
        EXPECT_THAT(e["message"].get<std::string>(), HasSubstr("s_2.vtu"));
    }
    b.send({{"type", "set"}, {"seq", 2}, {"step", 1}});
    const nlohmann::json fb = b.frame();
    ASSERT_FALSE(fb.is_null());
    EXPECT_EQ(fb["seq"], 2);
    a.send({{"type", "set"}, {"seq", 20}, {"step", 0}});
    const nlohmann::json fa = a.frame();
    ASSERT_FALSE(fa.is_null());
    EXPECT_EQ(fa["seq"], 20);
}

TEST(ViewServer, SoakOfHostileAndSlowClientsKeepsMemoryAndCpuBounded) {
    // Issue 28's soak: ~10 clients for about 30 s send a mix of valid and invalid messages
    // (deep nesting, oversized, bad types, the largest colour maps, exports), some never read.
    // Memory must stay flat after a warm-up, the CPU idle once they stop, and a well-behaved
    // tab must still be served at the end. Bounds are resources, not timings: generous.
    const auto seconds = std::chrono::seconds(
        std::getenv("UVR_SOAK_SECONDS") ? std::atoi(std::getenv("UVR_SOAK_SECONDS")) : 30);
    ServerOptions o;
    o.maxMessageBytes = 1 << 20;
    o.stalledWriteSeconds = 2.0;  // a tab that sent too much and never reads goes soon
    auto server = startServer(o);
    const std::string bigMap = colorMapJson(kMaxTfPoints);
    const std::string tooBig = colorMapJson(60000);   // ~1.3 MB: over maxMessageBytes
    const std::string tooMany = colorMapJson(20000);  // under it, over kMaxTfPoints
    const std::string deep =
        R"({"type":"set","range":)" + std::string(50000, '[') + std::string(50000, ']') + "}";
    std::atomic<bool> stop{false};
    std::atomic<std::uint64_t> sent{0};
    auto hostile = [&](int id, bool reads) {
        std::mt19937 rng(id);
        while (!stop) {
            try {
                Client c(server->port(), server->token());
                for (int i = 0; i < 400 && !stop; ++i) {
                    switch (rng() % 10) {
                        case 0:
                            c.sendText(deep);
                            break;
                        case 1:
                            c.send({{"type", "set"}, {"colormap_json", bigMap}});
                            break;
                        case 2:
                            c.send({{"type", "set"}, {"colormap_json", tooMany}});
                            break;
                        case 3:
                            c.send({{"type", "export"}});
                            break;
                        case 4:
                            c.send({{"type", 7}, {"seq", {1, 2}}});
                            break;
                        case 5:
                            c.sendText("{\"type\": \"set\", \"range\": [1, \"x\"]");
                            break;
                        case 6:
                            c.send({{"type", "set"},
                                    {"interactive", true},
                                    {"camera", {{"view_angle", 20 + int(rng() % 20)}}}});
                            break;
                        case 7:
                            c.send({{"type", "snapshot"}});
                            break;
                        case 8:
                            c.sendBinary(std::string(1000, '\1'));
                            break;
                        default:
                            if (rng() % 20 == 0)
                                c.sendText(tooBig);  // closes this one
                            else
                                c.send({{"type", "ping"}, {"seq", i}});
                    }
                    ++sent;
                    if (reads)
                        while (!c.next(1ms).is_null()) {
                        }
                    else
                        std::this_thread::sleep_for(2ms);
                }
            } catch (const std::exception&) {
                // closed by the server (too big, not reading): connect again
            }
        }
    };
    std::vector<std::thread> clients;
    for (int i = 0; i < 10; ++i) clients.emplace_back(hostile, i, i % 2 == 0);
    const auto start = std::chrono::steady_clock::now();
    std::this_thread::sleep_for(seconds / 4);  // warm-up: allocator pools, the first frames
    const std::size_t warm = residentBytes();
    std::size_t peak = warm;
    while (std::chrono::steady_clock::now() - start < seconds) {
        std::this_thread::sleep_for(500ms);
        peak = std::max(peak, residentBytes());
    }
    stop = true;
    for (std::thread& t : clients) t.join();
    EXPECT_GT(sent.load(), 1000u);
    // Growth after the warm-up: a few queues of bounded bytes, far from ~45 MB a second.
    EXPECT_LT(peak, warm + (96u << 20))
        << "warm " << (warm >> 20) << " MiB, peak " << (peak >> 20) << " MiB";
    // Quiet: the server's threads wait.
    std::this_thread::sleep_for(500ms);
    const double cpu0 = cpuSeconds();
    std::this_thread::sleep_for(2s);
    const double quietCpu = cpuSeconds() - cpu0;
    std::printf(
        "soak: %llu messages; RSS after warm-up %zu MiB, peak %zu MiB; CPU %.3f s over a "
        "quiet 2 s\n",
        static_cast<unsigned long long>(sent.load()), warm >> 20, peak >> 20, quietCpu);
    EXPECT_LT(quietCpu, 0.5) << "busy after the flood stopped";
    Client c(server->port(), server->token());
    ASSERT_EQ(c.next()["type"], "info");
    c.send({{"type", "set"}, {"seq", 99}, {"quality", 0.9}});
    nlohmann::json f = c.frame();  // the starting state's, then the change's
    for (int i = 0; i < 3 && !f.is_null() && f["seq"] != 99; ++i) f = c.frame();
    ASSERT_FALSE(f.is_null());
    EXPECT_EQ(f["seq"], 99);
}

}  // namespace
}  // namespace uvr::server
