// SPDX-License-Identifier: MIT
// A scripted browser for `uvr view`: connects to the WebSocket of a running viewer, orbits the
// camera as a dragging user would (interactive `set` messages at a fixed rate) and measures the
// input-to-frame-received latency and the frames received per second; then still changes
// (final `set` messages) and the time to their full-resolution frame. Prints one JSON object.
//
//   uvr_view_latency URL [--seconds 10] [--rate 60] [--size 1024x1024] [--still 20]
//                        [--switch-field NAME]  (also time a field change to its first frame)
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstdio>
#include <map>
#include <regex>

#include "uvr/render/camera.h"

namespace {

namespace beast = boost::beast;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Json = nlohmann::json;
using Clock = std::chrono::steady_clock;

double ms(Clock::duration d) {
    return std::chrono::duration<double, std::milli>(d).count();
}

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t i =
        std::min(v.size() - 1, static_cast<std::size_t>(p * (v.size() - 1) + 0.5));
    return v[i];
}

Json cameraJson(const uvr::Camera& c) {
    auto v = [](uvr::Vec3f a) { return Json::array({a.x, a.y, a.z}); };
    return {{"position", v(c.position)},
            {"focal_point", v(c.focalPoint)},
            {"view_up", v(c.viewUp)},
            {"view_angle", c.viewAngle}};
}

uvr::Camera cameraOf(const Json& j) {
    auto v = [](const Json& a) {
        return uvr::Vec3f(a[0].get<float>(), a[1].get<float>(), a[2].get<float>());
    };
    uvr::Camera c;
    c.position = v(j["position"]);
    c.focalPoint = v(j["focal_point"]);
    c.viewUp = v(j["view_up"]);
    c.viewAngle = j["view_angle"].get<float>();
    return c;
}

class Client {
public:
    explicit Client(const std::string& url) : ws_(ioc_) {
        std::smatch m;
        const std::regex re(R"(http://([^:/]+):(\d+)/\?token=([A-Za-z0-9_-]+))");
        if (!std::regex_search(url, m, re)) throw std::runtime_error("not a uvr view URL: " + url);
        tcp::resolver resolver(ioc_);
        net::connect(ws_.next_layer(), resolver.resolve(m[1].str(), m[2].str()));
        ws_.next_layer().set_option(tcp::no_delay(true));
        ws_.handshake(m[1].str() + ":" + m[2].str(), "/ws?token=" + m[3].str());
    }
    /// The next text message (binary images are skipped, their sizes summed).
    Json next() {
        for (;;) {
            beast::flat_buffer b;
            ws_.read(b);
            if (ws_.got_binary()) {
                imageBytes += b.size();
                continue;
            }
            return Json::parse(beast::buffers_to_string(b.data()));
        }
    }
    void send(const Json& j) {
        const std::string s = j.dump();
        ws_.text(true);
        ws_.write(net::buffer(s));
    }
    /// Reads in the background on its own thread from now on; frames go to onFrame.
    std::uint64_t imageBytes = 0;
    websocket::stream<tcp::socket>& ws() { return ws_; }

private:
    net::io_context ioc_;
    websocket::stream<tcp::socket> ws_;
};

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Measure uvr view's latency and frame rate with a scripted WebSocket client"};
    std::string url, size = "1024x1024";
    double seconds = 10.0, rate = 60.0, degrees = 1.0;
    int still = 20;
    std::string switchField;
    app.add_option("URL", url, "The URL uvr view printed")->required();
    app.add_option("--seconds", seconds, "Orbiting time")->capture_default_str();
    app.add_option("--rate", rate, "Camera events per second while orbiting")
        ->capture_default_str();
    app.add_option("--degrees", degrees, "Azimuth per event")->capture_default_str();
    app.add_option("--size", size, "Full-resolution image size WxH")->capture_default_str();
    app.add_option("--still", still, "Still changes to time")->capture_default_str();
    app.add_option("--switch-field", switchField,
                   "Finally switch to this field and time it until its frame arrives");
    CLI11_PARSE(app, argc, argv);
    int w = 0, h = 0;
    if (std::sscanf(size.c_str(), "%dx%d", &w, &h) != 2) {
        std::fprintf(stderr, "--size: expected WxH\n");
        return 2;
    }
    try {
        const auto t0 = Clock::now();
        Client c(url);
        Json info = c.next();
        if (info.value("type", "") != "info") throw std::runtime_error("no info message first");
        c.send({{"type", "set"}, {"seq", 1}, {"size", {w, h}}});
        uvr::Camera cam = cameraOf(info["state"]["camera"]);
        // Step 1: the first full frame at the size.
        for (;;) {
            const Json j = c.next();
            if (j.value("type", "") == "frame" && j["seq"] == 1 && j["full"].get<bool>()) break;
        }
        const double firstMs = ms(Clock::now() - t0);

        // Step 2: orbit. A reader thread records frames; this thread sends at the rate.
        std::map<std::uint64_t, Clock::time_point> sent;
        std::mutex mu;
        std::vector<double> latency, renderMs, scale, frameMs, encodeMs, bytes;
        std::atomic<bool> done{false};
        std::uint64_t frames = 0, reduced = 0;
        std::thread reader([&] {
            while (!done) {
                Json j;
                try {
                    j = c.next();
                } catch (...) {
                    return;
                }
                if (j.value("type", "") != "frame") continue;
                const auto now = Clock::now();
                std::lock_guard lk(mu);
                const std::uint64_t seq = j["seq"];
                if (auto it = sent.find(seq); it != sent.end() && seq >= 100) {
                    latency.push_back(ms(now - it->second));
                    renderMs.push_back(j["stats"]["render_seconds"].get<double>() * 1e3);
                    frameMs.push_back(j["stats"]["frame_seconds"].get<double>() * 1e3);
                    encodeMs.push_back(j["stats"]["encode_seconds"].get<double>() * 1e3);
                    bytes.push_back(j["stats"]["bytes"].get<double>());
                    scale.push_back(j["scale"].get<double>());
                    ++frames;
                    reduced += !j["full"].get<bool>();
                }
                if (seq == 0xFFFFFFFF) return;
            }
        });
        const auto period = std::chrono::duration<double>(1.0 / rate);
        const auto start = Clock::now();
        std::uint64_t seq = 100;
        while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
            cam = uvr::orbitCamera(cam, float(degrees), 0.f);
            {
                std::lock_guard lk(mu);
                sent[seq] = Clock::now();
            }
            c.send({{"type", "set"},
                    {"seq", seq},
                    {"interactive", true},
                    {"camera", cameraJson(cam)}});
            ++seq;
            std::this_thread::sleep_until(start + period * double(seq - 100));
        }
        const double orbitSeconds = std::chrono::duration<double>(Clock::now() - start).count();
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
        std::vector<double> movingLatency, movingRender, movingScale, movingFrame, movingEncode,
            movingBytes;
        std::uint64_t movingFrames, movingReduced;
        {
            std::lock_guard lk(mu);
            movingLatency = latency, movingRender = renderMs, movingScale = scale;
            movingFrame = frameMs, movingEncode = encodeMs, movingBytes = bytes;
            frameMs.clear(), encodeMs.clear(), bytes.clear();
            movingFrames = frames, movingReduced = reduced;
            latency.clear(), renderMs.clear(), frames = 0;
        }
        // Step 3: still changes, each waited for (its full frame), then a pause.
        std::vector<double> stillLatency;
        for (int i = 0; i < still; ++i) {
            cam = uvr::orbitCamera(cam, 5.f, 0.f);
            const std::uint64_t s = 1000000 + i;
            const auto t = Clock::now();
            {
                std::lock_guard lk(mu);
                sent[s] = t;
            }
            c.send({{"type", "set"}, {"seq", s}, {"camera", cameraJson(cam)}});
            for (int k = 0; k < 2000; ++k) {
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
                std::lock_guard lk(mu);
                if (!latency.empty()) break;
            }
            {
                std::lock_guard lk(mu);
                if (!latency.empty()) stillLatency.push_back(latency.back());
                latency.clear();
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(200));
        }
        // Step 4: a field change, timed to the frame that shows it.
        double switchMs = -1.0;
        if (!switchField.empty()) {
            const auto t = Clock::now();
            {
                std::lock_guard lk(mu);
                sent[2000000] = t;
                latency.clear();
            }
            c.send({{"type", "set"}, {"seq", 2000000}, {"field", switchField}});
            for (int k = 0; k < 600000; ++k) {
                std::this_thread::sleep_for(std::chrono::milliseconds(1));
                std::lock_guard lk(mu);
                if (!latency.empty()) {
                    switchMs = latency.back();
                    break;
                }
            }
        }
        done = true;
        c.ws().next_layer().shutdown(tcp::socket::shutdown_both);
        reader.join();
        Json out = {{"size", {w, h}},
                    {"device", info["device"]},
                    {"tetrahedra", info["tetrahedra"]},
                    {"first_full_frame_ms", firstMs},
                    {"field_switch_ms", switchMs},
                    {"orbit",
                     {{"seconds", orbitSeconds},
                      {"events", seq - 100},
                      {"event_rate", double(seq - 100) / orbitSeconds},
                      {"frames", movingFrames},
                      {"reduced_frames", movingReduced},
                      {"updates_per_second", double(movingFrames) / orbitSeconds},
                      {"latency_ms_median", percentile(movingLatency, 0.5)},
                      {"latency_ms_p95", percentile(movingLatency, 0.95)},
                      {"render_ms_median", percentile(movingRender, 0.5)},
                      {"frame_ms_median", percentile(movingFrame, 0.5)},
                      {"encode_ms_median", percentile(movingEncode, 0.5)},
                      {"bytes_median", percentile(movingBytes, 0.5)},
                      {"scale_median", percentile(movingScale, 0.5)}}},
                    {"still",
                     {{"changes", stillLatency.size()},
                      {"latency_ms_median", percentile(stillLatency, 0.5)},
                      {"latency_ms_p95", percentile(stillLatency, 0.95)},
                      {"frame_ms_median", percentile(frameMs, 0.5)},
                      {"encode_ms_median", percentile(encodeMs, 0.5)},
                      {"bytes_median", percentile(bytes, 0.5)}}}};
        std::printf("%s\n", out.dump(2).c_str());
    } catch (const std::exception& e) {
        std::fprintf(stderr, "uvr_view_latency: %s\n", e.what());
        return 1;
    }
    return 0;
}
