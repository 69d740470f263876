// SPDX-License-Identifier: MIT
#include "uvr/server/view_server.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "http_connection.h"
#include "server_internal.h"
#include "session.h"

#include "uvr/core/error.h"
#include "uvr/core/text.h"
#include "uvr/dist/decompose.h"
#include "uvr/facade/frame_report.h"
#include "uvr/mesh/cell_types.h"
#include "uvr/render/heatmap.h"
#include "uvr/render/image.h"
#include "uvr/render/settings_vocabulary.h"
#include "uvr/server/view_frame.h"
#include "uvr/tf/transfer_function.h"

namespace uvr::server {

namespace {

/// Bins of the field histograms the page draws.
constexpr int kHistogramBins = 256;
/// Descriptors kept free of connections below the process's limit (files of time steps, the
/// log, the render thread's needs).
constexpr int kReservedDescriptors = 32;
/// The first and longest wait before accepting again after accept failed (EMFILE: no
/// descriptor left), and the least time between two log lines about it.
constexpr auto kAcceptRetryFirst = std::chrono::milliseconds(10);
constexpr auto kAcceptRetryMax = std::chrono::milliseconds(1000);
constexpr auto kAcceptLogInterval = std::chrono::seconds(10);

double secondsSince(Clock::time_point t) {
    return std::chrono::duration<double>(Clock::now() - t).count();
}

/// Least time between two "progress" messages of a phase with fractions.
constexpr double kProgressInterval = 0.1;

/// A preparation's progress as "progress" messages given to `send`: each phase's name with
/// fraction null when it starts (`onStep` hears the name first, when set), then its fractions
/// at most every kProgressInterval seconds and its end (1) always. Callable from any thread.
ProgressFn progressMessages(std::function<void(const std::string&)> send,
                            std::function<void(const std::string&)> onStep = {}) {
    struct Phase {
        std::mutex m;
        std::string name;
        Clock::time_point last;
    };
    auto phase = std::make_shared<Phase>();
    auto message = [](const std::string& name, const Json& fraction) {
        return Json{{"type", "progress"}, {"phase", name}, {"fraction", fraction}}.dump(
            -1, ' ', false, Json::error_handler_t::replace);
    };
    return {[=](const std::string& name) {
                if (onStep) onStep(name);
                {
                    std::lock_guard lk(phase->m);
                    phase->name = name;
                    phase->last = Clock::now();
                }
                send(message(name, nullptr));
            },
            [=](double f) {
                std::string text;
                {
                    std::lock_guard lk(phase->m);
                    if (f < 1.0 && secondsSince(phase->last) < kProgressInterval) return;
                    phase->last = Clock::now();
                    text = message(phase->name, f);
                }
                send(text);
            }};
}

std::string randomToken() {
    std::random_device rd;  // /dev/urandom on Linux
    static const char* hex = "0123456789abcdef";
    std::string t;
    for (int i = 0; i < 32; ++i) t += hex[rd() & 15];
    return t;
}

/// "uvr render" arguments quoted for a POSIX shell where needed.
std::string shellQuote(const std::string& arg) {
    const bool plain = !arg.empty() && std::all_of(arg.begin(), arg.end(), [](unsigned char c) {
        return std::isalnum(c) || std::string_view("_-./:,=+@%").find(c) != std::string_view::npos;
    });
    if (plain) return arg;
    std::string out = "'";
    for (char c : arg) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// The shortest decimal that reads back as the same float.
std::string fmtExact(float v) {
    char buf[40];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
        if (std::strtof(buf, nullptr) == v) break;
    }
    return buf;
}

std::vector<std::uint64_t> histogramCounts(const std::vector<float>& values,
                                           std::pair<float, float> range) {
    std::vector<std::uint64_t> counts(kHistogramBins, 0);
    const double lo = range.first, hi = range.second;
    const double scale = hi > lo ? kHistogramBins / (hi - lo) : 0.0;
    for (float v : values) {
        if (!std::isfinite(v)) continue;
        const int bin = std::clamp(static_cast<int>((v - lo) * scale), 0, kHistogramBins - 1);
        ++counts[bin];
    }
    return counts;
}

}  // namespace

ScalarField ViewServer::Impl::valuesOf(const std::string& spec) const {
    const FieldSpec fs = parseFieldSpec(spec);
    if (!scene.part) return selectScalarField(*scene.mesh, fs);
    // The listed fields carry the whole mesh's constancy: the default is every rank's.
    FieldChoice choice = resolveField(fieldInfos, fs);
    FieldSpec pinned = fs;
    pinned.name = scene.mesh->fields[choice.index].name;
    pinned.association = scene.mesh->fields[choice.index].association;
    ScalarField field = selectScalarField(*scene.mesh, pinned);
    field.choice = std::move(choice.choice);
    return field;
}

FieldEntry ViewServer::Impl::entryOf(const std::vector<float>& values) const {
    FieldEntry entry;
    Communicator* comm = scene.part ? ranks() : nullptr;
    entry.range = comm ? reduceFiniteRange(*comm, values) : finiteRange(values);
    std::vector<std::uint64_t> counts = histogramCounts(values, entry.range);
    if (comm) comm->allReduce(std::span<std::uint64_t>(counts), ReduceOp::Sum);
    entry.histogram = {{"range", {entry.range.first, entry.range.second}}, {"counts", counts}};
    return entry;
}

Communicator* ViewServer::Impl::ranks() const {
    Communicator* comm = scene.rendererOptions.communicator;
    return comm && comm->size() > 1 ? comm : nullptr;
}

void ViewServer::Impl::lead(const Json& call) {
    Communicator* comm = ranks();
    if (!comm || comm->rank() != 0) return;
    const std::string text = call.dump();
    for (int r = 1; r < comm->size(); ++r)
        comm->send(r, std::as_bytes(std::span<const char>(text.data(), text.size())));
}

void ViewServer::Impl::releaseFollowers() {
    if (followersReleased) return;
    followersReleased = true;
    lead({{"call", "stop"}});
}

ViewFrame ViewServer::Impl::frame(const ViewState& state, FrameKind kind, int scale,
                                  std::uint64_t seq, const FrameEncoding& encoding) {
    lead({{"call", "frame"},
          {"state", toJson(state)},
          {"kind", static_cast<int>(kind)},
          {"scale", scale}});
    return renderViewFrame(*renderer, state, scene.base, kind, scale, seq, encoding);
}

FieldEntry ViewServer::Impl::field(const std::string& spec, std::size_t step,
                                   const ProgressFn& progress) {
    lead({{"call", "field"}, {"spec", spec}, {"step", step}});
    const std::string key = fieldKey(spec, step);
    if (renderer && key == rendererKey) {
        std::lock_guard lk(fieldsMutex);
        return fields.at(key);
    }
    if (scene.fromCache)
        throwError(ErrorKind::Unsupported, scene.fromCache->file,
                   "served from this prepared cache, which holds " +
                       scene.fromCache->summary.field().describe() +
                       " alone: `uvr view --no-cache` reads the mesh, to show other fields");
    // Data-parallel, every rank reads the step: a rank that fails ends every rank's call.
    const auto agreed = [this](auto&& work) {
        if (Communicator* comm = ranks())
            agreeOn(*comm, work);
        else
            work();
    };
    if (step != meshStep)
        agreed([&] {
            // Another time step: its fields for the same points and cells, nothing geometric.
            const auto start = Clock::now();
            std::optional<std::vector<Field>> stepFields;
            if (scene.part) {  // this rank's run of the step's parts
                const auto [first, end] = rankRunOfStep(*scene.series, step, *ranks());
                MeshPart part = scene.series->readPart(step, first, end);
                if (samePartGeometry(part, *scene.mesh, scene.part->pointIds, scene.part->cellIds))
                    stepFields = std::move(part.mesh.fields);
            } else {
                stepFields = scene.series->readFieldsIfSameGeometry(step, *scene.mesh);
            }
            if (!stepFields)
                throwError(
                    ErrorKind::Unsupported, scene.series->stepSource(step),
                    "time step " + std::to_string(step) +
                        " has other points or cells than "
                        "step " +
                        std::to_string(meshStep) +
                        ": the viewer shows the time steps of one geometry (uvr animate renders "
                        "any)");
            // The two lists compared as listed (names, associations, components): whether a field
            // holds one value is the step's values, not its list.
            std::vector<FieldInfo> infos, listed = fieldInfos;
            for (const Field& f : *stepFields)
                infos.push_back({f.name, f.association, f.components});
            for (FieldInfo& f : listed) f.constant = false;
            if (resolveField(infos, parseFieldSpec(spec)).index !=
                resolveField(listed, parseFieldSpec(spec)).index)
                throwError(ErrorKind::Unsupported, scene.series->stepSource(step),
                           "time step " + std::to_string(step) +
                               " lists its fields otherwise than "
                               "step " +
                               std::to_string(meshStep) + ": the viewer needs the same fields");
            scene.mesh->fields = std::move(*stepFields);
            meshStep = step;
            char line[160];
            std::snprintf(line, sizeof line, "view: read time step %zu (time %.9g) in %.3f s", step,
                          scene.series->times()[step], secondsSince(start));
            say(line);
        });
    ScalarField values;
    agreed([&] { values = valuesOf(spec); });
    FieldEntry entry = entryOf(values.values);
    const auto start = Clock::now();
    char line[200];
    if (!renderer) {
        say("view: preparing " + values.describe());
        if (const auto& part = scene.part)  // this rank's part, as readDistributed gave it
            renderer = std::make_unique<Renderer>(
                MeshShare{*scene.mesh, values, part->pointIds, part->cellIds},
                scene.rendererOptions, progress);
        else
            renderer =
                std::make_unique<Renderer>(*scene.mesh, values, scene.rendererOptions, progress);
        std::snprintf(line, sizeof line, "view: prepared %s in %.2f s", values.describe().c_str(),
                      secondsSince(start));
    } else {
        // The same mesh: only the values and what depends on them change. Until that is done
        // the renderer holds no field known by key (a failure leaves it to be set again).
        rendererKey.clear();
        renderer->setFieldValues(values);
        std::snprintf(line, sizeof line, "view: switched to %s in %.3f s (no geometry rebuilt)",
                      values.describe().c_str(), secondsSince(start));
    }
    rendererKey = key;
    say(line);
    std::lock_guard lk(fieldsMutex);
    return fields[key] = std::move(entry);
}

/// The vocabulary's entries of the settings the page sets (kViewerSettings): their choices,
/// ranges and docs for its controls.
static Json viewerVocabulary(const std::vector<std::string>& methods) {
    Json out = Json::array();
    for (Json d : settingsVocabularyJson()) {
        const std::string name = d["name"].get<std::string>();
        if (!isViewerSetting(name)) continue;
        if (name == "method") d["choices"] = methods;
        out.push_back(d);
    }
    return out;
}

Json ViewServer::Impl::exportMessage(const ViewState& state) const {
    ViewState s = state;
    // A log scale over a range from 0 or below maps as the frames do (ParaView's
    // AdjustRangeForLog, makeFrameSetup): export the range they use.
    if (s.tf.logScale && !(s.range.first > 0.f) && s.range.second > 0.f)
        s.range.first = std::fmin(s.range.second * 1e-4f, 1.f);
    std::vector<std::string> args = {"uvr", "render", scene.file};
    if (stepCount() > 1) args.insert(args.end(), {"--step-index", std::to_string(s.step)});
    const std::string field = scene.fromCache ? scene.fromCache->fieldSpec : s.field;
    if (!field.empty()) args.insert(args.end(), {"--field", field});
    // The state's settings as the frames use them (the command line's where the page set none).
    const RenderSettings f = frameSettings(s, scene.base);
    args.insert(args.end(), {"--tf", "uvr-tf.json", "--camera", "uvr-camera.pvcc", "--range",
                             fmtExact(s.range.first) + "," + fmtExact(s.range.second), "--size",
                             std::to_string(s.width) + "x" + std::to_string(s.height)});
    // The page's settings by their flags: the method always, the others where they are not the
    // default (the opacity unit always is: the server sets it to ParaView's), and what tunes the
    // adaptive method when it renders.
    // A setting whose `needs` is off is not read (and the command line refuses it then).
    for (const char* name : kViewerSettings) {
        const SettingDef& def = settingNamed(name);
        const Json value = def.get(f);
        if (std::string_view(def.name) != "method" && value == settingDefault(def) &&
            !(def.tunesAdaptive && f.method == RenderMethod::Partitions))
            continue;
        if (!settingNeedMet(def, f)) continue;
        // The face box kept on with the clip off draws nothing, and the command line refuses it.
        if (std::string_view(def.name) == "clip_surface" && f.clipPlanes.empty() && !f.clipBox)
            continue;
        args.push_back(cliFlag(def));  // a flag's is its value ("--shade", "--no-skip")
        if (def.type != SettingType::Flag)
            args.push_back(value.is_string() ? value.get<std::string>()
                                             : fmtExact(value.get<float>()));
    }
    // The page's clip planes (the command line's clip box comes with its flags).
    for (const ClipPlane& p : s.clipPlanes) {
        std::string plane;
        for (const float x :
             {p.origin.x, p.origin.y, p.origin.z, p.normal.x, p.normal.y, p.normal.z})
            plane += (plane.empty() ? "" : ",") + fmtExact(x);
        args.insert(args.end(), {"--clip-plane", plane});
    }
    for (const IsoSurface& iso : s.isoSurfaces) args.insert(args.end(), {"--iso", isoText(iso)});
    if (s.gradientOpacity.active())
        args.insert(args.end(), {"--gradient-opacity", gradientOpacityText(s.gradientOpacity)});
    args.insert(args.end(), scene.commandFlags.begin(), scene.commandFlags.end());
    // The background the page shows (uvr render's default is a transparent PNG).
    args.insert(args.end(),
                {"--background", fmtExact(s.background.x) + "," + fmtExact(s.background.y) + "," +
                                     fmtExact(s.background.z)});
    args.insert(args.end(), {"-o", "uvr-view.png"});
    std::string command;
    for (const std::string& a : args) command += (command.empty() ? "" : " ") + shellQuote(a);
    return {{"type", "export"},
            {"tf_json", paraViewColorMapJson(s.tf, s.range.first, s.range.second)},
            {"pvcc", pvccText(s.camera)},
            {"tf_file", "uvr-tf.json"},
            {"camera_file", "uvr-camera.pvcc"},
            {"command", command}};
}

void ViewServer::Impl::broadcast(const std::string& text, std::string_view supersedes) {
    net::post(ioc, [this, text, supersedes] {
        std::vector<std::shared_ptr<Session>> live;
        {
            std::lock_guard lk(m);
            for (const auto& w : sessions)
                if (auto s = w.lock()) live.push_back(std::move(s));
        }
        for (const auto& s : live) s->sendText(text, supersedes);
    });
}

void ViewServer::Impl::prepareAtStart() {
    if (renderer) return;
    const auto start = Clock::now();
    try {
        field(scene.initial.field, scene.initial.step,
              progressMessages([this](const std::string& text) { broadcast(text, "progress"); },
                               [this](const std::string& phase) { say("view: " + phase); }));
    } catch (const std::exception& e) {
        // Said to the log and the page; the first frame tries again and answers with the error.
        say(std::string("view: preparation failed: ") + e.what());
        broadcast(Json{{"type", "error"},
                       {"message", printableShort(e.what(), kMaxErrorBytes)},
                       {"request", "prepare"}}
                      .dump(-1, ' ', false, Json::error_handler_t::replace));
        return;
    }
    Json prepared = {{"type", "prepared"},
                     {"tetrahedra", renderer->prepared().tets.tetCount()},
                     {"rendered_cells", describeCells(renderer->prepared().tets)},
                     {"prepare_seconds", secondsSince(start)},
                     {"device", renderer->deviceDescription()}};
    {
        std::lock_guard lk(m);
        for (const char* key : {"tetrahedra", "rendered_cells", "prepare_seconds", "device"})
            infoBase[key] = prepared[key];
    }
    broadcast(prepared.dump());
}

void ViewServer::Impl::renderLoop() {
    prepareAtStart();
    const ScheduleOptions schedule{std::chrono::milliseconds(opt.refineDelayMs), opt.targetFrameMs,
                                   opt.maxScale};
    const FrameEncoding encoding{opt.jpegQuality};
    std::unique_lock lk(m);
    while (!stopping) {
        // Step 1: the next tab with work (frame_scheduler.h), or wait for one.
        std::vector<std::shared_ptr<Session>> live(sessions.size());
        std::vector<const FrameDemand*> demands(sessions.size());
        for (std::size_t i = 0; i < sessions.size(); ++i)
            if ((live[i] = sessions[i].lock())) demands[i] = &live[i]->demand;
        const FramePick pick = pickFrame(demands, roundRobin, Clock::now(), schedule);
        // The last reference to a closed connection goes on the network thread, which owns its
        // socket.
        const auto release = [this](std::vector<std::shared_ptr<Session>>& refs) {
            net::post(ioc, [refs = std::move(refs)] {});
            refs.clear();
        };
        if (!pick.tab) {
            release(live);
            if (pick.wakeAt == Clock::time_point::max())
                cv.wait(lk);
            else
                cv.wait_until(lk, pick.wakeAt);
            continue;
        }
        roundRobin = *pick.tab + 1;
        std::shared_ptr<Session> s = live[*pick.tab];
        release(live);
        // Step 2: take the state; newer changes wait for this frame to be sent.
        const FrameKind kind = pick.kind;
        ViewState state = s->state;
        const std::uint64_t seq = s->seq;
        const int scale =
            kind == FrameKind::Reduced
                ? reducedScale(s->demand, double(state.width) * state.height, schedule)
                : 1;
        s->demand.start(kind);
        const bool resetRange = s->resetRange;
        const std::string histogramKey = s->histogramKey;
        s->resetRange = false;
        lk.unlock();

        // Step 3: the field (prepared or swapped in), then the frame, outside the lock.
        std::weak_ptr<Session> weak = s;
        auto post = [&](std::function<void(Session&)> f) {
            net::post(ioc, [weak, f = std::move(f)] {
                if (auto c = weak.lock()) f(*c);
            });
        };
        bool sent = false;
        try {
            const std::string key = fieldKey(state.field, state.step);
            const FieldEntry entry =
                field(state.field, state.step, progressMessages([&](const std::string& text) {
                          post([text](Session& c) { c.sendText(text, "progress"); });
                      }));
            if (resetRange) {
                state.range = entry.range;
                if (!(state.range.first < state.range.second))
                    state.range.second = state.range.first + 1.f;
                std::lock_guard slk(m);
                s->state.range = state.range;
            }
            if (key != histogramKey || resetRange) {
                {
                    std::lock_guard slk(m);
                    s->histogramKey = key;
                }
                Json h = entry.histogram;
                h["type"] = "histogram";
                h["field"] = state.field;
                Json st = {{"type", "state"}, {"state", toJson(state)}};
                post([h = h.dump(), st = st.dump()](Session& c) {
                    c.sendText(h, "histogram");
                    c.sendText(st, "state");
                });
            }
            ViewFrame frame = this->frame(state, kind, scale, seq, encoding);
            {
                std::lock_guard slk(m);
                s->demand.measured(frame.msPerPixel, kind == FrameKind::Reduced ? scale : 0);
            }
            post([meta = frame.meta.dump(), bytes = std::move(frame.bytes)](Session& c) mutable {
                c.sendImage(meta, std::string(bytes.begin(), bytes.end()));
            });
            sent = true;
        } catch (const std::exception& e) {
            // A step or field that fails to read (uvr::Error, bad_alloc, anything): this tab
            // hears why, the server goes on serving it and the others.
            const std::string message = printableShort(e.what(), kMaxErrorBytes);
            say("view: frame failed: " + message);
            post([message](Session& c) { c.sendError(message, "frame"); });
        } catch (...) {
            say("view: frame failed: unknown exception");
            post([](Session& c) { c.sendError("failed (unknown exception)", "frame"); });
        }
        lk.lock();
        if (!sent) s->demand.finished();
        // The last reference to a closed connection goes on the network thread, which owns
        // its socket.
        net::post(ioc, [s = std::move(s)] {});
    }
}

void ViewServer::Impl::acceptLoop() {
    if (!acceptor.is_open()) return;
    acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
        if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
        if (ec) return acceptFailed(ec);
        acceptDelay = std::chrono::milliseconds(0);
        admitConnection(std::move(socket));
        acceptLoop();
    });
}

void ViewServer::Impl::acceptFailed(const beast::error_code& ec) {
    // Retrying at once would spin: a descriptor frees only when a connection ends.
    ++acceptFailures;
    acceptDelay =
        acceptDelay.count() == 0 ? kAcceptRetryFirst : std::min(acceptDelay * 2, kAcceptRetryMax);
    const bool noDescriptor = ec.value() == EMFILE || ec.value() == ENFILE;
    const bool freed = noDescriptor && closeOldestHttp();
    const auto now = Clock::now();
    if (now - lastAcceptLog >= kAcceptLogInterval) {
        lastAcceptLog = now;
        say("view: accept failed (" + ec.message() + "; " + std::to_string(acceptFailures) +
            " failure(s) so far): " + (freed ? "closed the oldest page connection, " : "") +
            "retrying in " + std::to_string(acceptDelay.count()) + " ms");
    }
    acceptRetry.expires_after(acceptDelay);
    acceptRetry.async_wait([this](beast::error_code wait) {
        if (!wait) acceptLoop();
    });
}

bool ViewServer::Impl::closeOldestHttp() {
    while (!httpConnections.empty()) {
        auto c = httpConnections.front().lock();
        httpConnections.pop_front();
        if (c) {
            c->close();
            return true;
        }
    }
    return false;
}

void ViewServer::Impl::admitConnection(tcp::socket socket) {
    httpConnections.erase(std::remove_if(httpConnections.begin(), httpConnections.end(),
                                         [](const auto& w) { return w.expired(); }),
                          httpConnections.end());
    std::size_t sessionCount = 0;
    {
        std::lock_guard lk(m);
        for (const auto& w : sessions) sessionCount += !w.expired();
    }
    if (httpConnections.size() + sessionCount >= static_cast<std::size_t>(connectionCap) &&
        !closeOldestHttp()) {
        beast::error_code ignored;
        socket.close(ignored);  // every place is a WebSocket: the newcomer waits its turn
        return;
    }
    // Frames go out as two messages (description, image): no Nagle delay between them.
    beast::error_code ignored;
    socket.set_option(tcp::no_delay(true), ignored);
    auto c = std::make_shared<HttpConnection>(*this, std::move(socket));
    httpConnections.push_back(c);
    c->start();
}

void ViewServer::Impl::requestStop() {
    {
        std::lock_guard lk(m);
        if (stopping) return;
        stopping = true;
    }
    cv.notify_all();
}

namespace {

/// The address of the options' host ("localhost" is 127.0.0.1); Error(Argument) when it is not
/// an IP address.
net::ip::address hostAddress(const ServerOptions& o) {
    if (o.host == "localhost") return net::ip::address_v4::loopback();
    beast::error_code ec;
    const auto address = net::ip::make_address(o.host, ec);
    if (ec)
        throwError(
            ErrorKind::Argument, "",
            "`host` " + printableShort(o.host, 60) + ": not an IP address (" + ec.message() + ")");
    return address;
}

/// Opens, binds and (with `listen`) listens on the options' address; Error(Io) naming it.
void bindTo(tcp::acceptor& acceptor, const ServerOptions& o, bool listen) {
    const tcp::endpoint endpoint(hostAddress(o), o.port);
    beast::error_code ec;
    acceptor.open(endpoint.protocol(), ec);
    if (!ec) acceptor.set_option(net::socket_base::reuse_address(true), ec);
    if (!ec) acceptor.bind(endpoint, ec);
    if (!ec && listen) acceptor.listen(net::socket_base::max_listen_connections, ec);
    if (ec)
        throwError(
            ErrorKind::Io, "",
            "cannot listen on " + o.host + ":" + std::to_string(o.port) + ": " + ec.message());
}

}  // namespace

void checkServerOptions(const ServerOptions& o, bool tryAddress) {
    if (!o.token.empty()) {
        const bool ok = o.token.size() >= kMinTokenLength &&
                        std::all_of(o.token.begin(), o.token.end(), [](unsigned char c) {
                            return std::isalnum(c) || c == '_' || c == '-';
                        });
        if (!ok)
            throwError(ErrorKind::Argument, "",
                       "`token`: expected " + std::to_string(kMinTokenLength) +
                           " or more characters from A-Z, a-z, 0-9, _ and -");
    }
    if (o.maxSessions < 1 || o.maxMessagesPerSecond < 1 || o.maxScale < 1 || o.maxConnections < 1 ||
        o.maxMessageBytes < 1 || o.maxQueuedBytes < 1 || !(o.idleSeconds > 0.0) ||
        !(o.stalledWriteSeconds > 0.0))
        throwError(ErrorKind::Argument, "", "server limits must be positive");
    if (!(o.targetFrameMs >= kMinTargetFrameMs && o.targetFrameMs <= kMaxTargetFrameMs))
        throwError(ErrorKind::Argument, "",
                   "`moving_frame_ms` " + formatG(o.targetFrameMs, 6) + ": expected a number in [" +
                       formatG(kMinTargetFrameMs, 6) + ", " + formatG(kMaxTargetFrameMs, 6) + "]");
    hostAddress(o);
    if (tryAddress) {
        net::io_context ioc;
        tcp::acceptor probe(ioc);
        bindTo(probe, o, false);
    }
}

ViewServer::ViewServer(ViewScene scene, ServerOptions options, LogFn log)
    : impl_(std::make_unique<Impl>()) {
    Impl& d = *impl_;
    if (!scene.mesh && !(scene.fromCache && scene.renderer))
        throwError(ErrorKind::Argument, "", "the viewer needs a mesh, or a prepared one");
    if ((scene.fromCache || (scene.part && !scene.part->steps)) && scene.series)
        throwError(ErrorKind::Argument, "",
                   scene.fromCache ? "a prepared cache holds one time step"
                                   : "a series read by parts needs its run of parts");
    checkServerOptions(options, false);
    if (options.token.empty()) options.token = randomToken();
    d.scene = std::move(scene);
    d.opt = std::move(options);
    d.log = std::move(log);
    // The fields as the page lists them, with their ranges and their values' constancy, so that
    // the default resolves as selectScalarField does; from a prepared cache, its one field.
    Json fields = Json::array();
    std::map<std::string, std::uint64_t> types;
    std::uint64_t cellCount = 0, pointCount = 0;
    std::vector<float> firstValues;  // the starting field's
    if (const auto& cached = d.scene.fromCache) {
        const TetMesh& t = d.scene.renderer->prepared().tets;
        d.fieldInfos = {{cached->summary.fieldName, cached->summary.association, 1}};
        fields.push_back({{"name", cached->summary.fieldName},
                          {"association", associationName(cached->summary.association)},
                          {"components", 1},
                          {"range", {t.valueMin, t.valueMax}},
                          {"default", true}});
        // The rendered cells' kinds (the file's are not read).
        for (const auto& [type, n] : {std::pair{CellType::Tetra, t.tetCount()},
                                      {CellType::Pyramid, t.pyramidCount},
                                      {CellType::Wedge, t.wedgeCount},
                                      {CellType::Hexahedron, t.hexCount}})
            if (n) types[cellTypeName(type)] = n;
        cellCount = cached->summary.cells;
        pointCount = cached->summary.points;
        d.scene.initial.field.clear();  // the one field, by any spec the cache was made for
        firstValues = preparedValues(d.scene.renderer->prepared());
    } else {
        const Mesh& mesh = *d.scene.mesh;
        // The ranks' parts: which fields hold one value over the whole mesh (as shareOfPart
        // decides) and the listed ranges, reduced.
        Communicator* comm = d.scene.part ? d.ranks() : nullptr;
        d.fieldInfos = comm ? reducedFieldInfos(*comm, mesh) : uvr::fieldInfos(mesh);
        std::vector<std::pair<float, float>> ranges;
        for (const Field& f : mesh.fields) {
            const std::vector<float> values = scalarFieldOf(mesh, f).values;
            ranges.push_back(comm ? reduceFiniteRange(*comm, values) : finiteRange(values));
        }
        const std::optional<std::size_t> def = defaultFieldIndex(d.fieldInfos);
        for (std::size_t i = 0; i < mesh.fields.size(); ++i) {
            const Field& f = mesh.fields[i];
            fields.push_back({{"name", f.name},
                              {"association", associationName(f.association)},
                              {"components", f.components},
                              {"range", {ranges[i].first, ranges[i].second}},
                              {"default", def == i}});
        }
        if (comm) {  // every rank's cells, by kind
            constexpr CellType kinds[] = {CellType::Tetra, CellType::Pyramid, CellType::Wedge,
                                          CellType::Hexahedron};
            std::uint64_t n[4] = {0, 0, 0, 0};
            for (CellType t : mesh.cellTypes)
                for (int k = 0; k < 4; ++k) n[k] += t == kinds[k];
            comm->allReduce(std::span<std::uint64_t>(n, 4), ReduceOp::Sum);
            for (int k = 0; k < 4; ++k)
                if (n[k]) types[cellTypeName(kinds[k])] = n[k];
            cellCount = d.scene.part->cells;
            pointCount = d.scene.part->points;
        } else {
            for (CellType t : mesh.cellTypes) ++types[cellTypeName(t)];
            cellCount = mesh.cellCount();
            pointCount = mesh.pointCount();
        }
    }
    d.fieldKey(d.scene.initial.field);  // the starting field exists
    const Bounds3f& b = d.scene.bounds;
    std::vector<std::string> presets;
    for (const ColorMapInfo& p : transferFunctionPresets()) presets.push_back(p.name);
    // The command line's preparation serves the starting field.
    // Unknown (null) until the server's own preparation is done (prepareAtStart).
    Json tets = nullptr, renderedCells = nullptr, prepareSeconds = nullptr;
    std::string device = resolvesToCuda(d.scene.rendererOptions.device) ? "cuda" : "cpu";
    const ViewState& first = d.scene.initial;
    if (first.width < kMinViewSize || first.height < kMinViewSize || first.width > kMaxViewSize ||
        first.height > kMaxViewSize)
        throwError(ErrorKind::Argument, "",
                   "image size " + std::to_string(first.width) + "x" +
                       std::to_string(first.height) + ": the viewer's sides are from " +
                       std::to_string(kMinViewSize) + " to " + std::to_string(kMaxViewSize) +
                       " pixels");
    d.meshStep = d.scene.initial.step;
    if (d.meshStep >= d.stepCount())
        throwError(
            ErrorKind::Argument, d.scene.file,
            "time step " + std::to_string(d.meshStep) + " of " + std::to_string(d.stepCount()));
    if (!d.scene.fromCache) firstValues = d.valuesOf(d.scene.initial.field).values;
    d.fields[d.fieldKey(d.scene.initial.field, d.meshStep)] = d.entryOf(firstValues);
    // Every method, or those a prepared cache holds.
    std::vector<std::string> methods = methodNames();
    if (d.scene.fromCache) {
        methods.clear();
        for (RenderMethod m : renderableMethods(d.scene.renderer->prepared()))
            methods.push_back(methodName(m));
    }
    if (d.scene.renderer) {
        tets = d.scene.renderer->prepared().tets.tetCount();
        renderedCells = describeCells(d.scene.renderer->prepared().tets);
        prepareSeconds = d.scene.renderer->prepareSeconds();
        device = d.scene.renderer->deviceDescription();
        d.renderer = std::move(d.scene.renderer);
        d.rendererKey = d.fieldKey(d.scene.initial.field, d.meshStep);
    }
    d.infoBase = {{"type", "info"},
                  {"file", d.scene.file},
                  {"cells", cellCount},
                  {"points", pointCount},
                  {"tetrahedra", tets},
                  {"rendered_cells", renderedCells},
                  {"cell_types", types},
                  {"bounds", {{b.lo.x, b.lo.y, b.lo.z}, {b.hi.x, b.hi.y, b.hi.z}}},
                  {"fields", fields},
                  {"presets", presets},
                  {"methods", methods},
                  {"settings", viewerVocabulary(methods)},
                  {"device", device},
                  {"load_seconds", d.scene.loadSeconds},
                  {"prepare_seconds", prepareSeconds},
                  {"notes", d.scene.notes},
                  {"fit_size", !d.scene.sizeGiven},
                  {"times", d.scene.series ? d.scene.series->times() : std::vector<double>{0.0}},
                  {"limits",
                   {{"max_message_bytes", d.opt.maxMessageBytes},
                    {"max_messages_per_second", d.opt.maxMessagesPerSecond},
                    {"min_size", kMinViewSize},
                    {"max_size", kMaxViewSize},
                    {"max_tf_points", kMaxTfPoints},
                    {"max_clip_planes", kMaxClipPlanes},
                    {"max_iso", kMaxIsoSurfaces}}}};
}

ViewServer::~ViewServer() {
    stop();
    Impl& d = *impl_;
    if (d.renderThread.joinable()) d.renderThread.join();
    try {
        d.releaseFollowers();
    } catch (...) {  // a destructor does not throw: the ranks were lost already
    }
    d.ioc.stop();
    if (d.ioThread.joinable()) d.ioThread.join();
}

void ViewServer::start() {
    Impl& d = *impl_;
    if (d.started) return;
    bindTo(d.acceptor, d.opt, true);
    d.boundPort = d.acceptor.local_endpoint().port();
    // Connections stay below the descriptor limit, so that accept rarely finds none left.
    d.connectionCap = d.opt.maxConnections;
    rlimit files{};
    if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY)
        d.connectionCap = static_cast<int>(std::max<rlim_t>(
            1, std::min<rlim_t>(d.connectionCap, files.rlim_cur > kReservedDescriptors
                                                     ? files.rlim_cur - kReservedDescriptors
                                                     : 1)));
    d.acceptLoop();
    d.started = true;
    d.ioThread = std::thread([&d] { d.ioc.run(); });
    d.renderThread = std::thread([&d] { d.renderLoop(); });
}

std::uint16_t ViewServer::port() const {
    return impl_->boundPort;
}

const std::string& ViewServer::token() const {
    return impl_->opt.token;
}

std::string ViewServer::url() const {
    std::string host = impl_->opt.host;
    if (host == "0.0.0.0" || host == "::") {
        char name[256] = {};
        host = gethostname(name, sizeof name - 1) == 0 && name[0] ? name : "localhost";
    } else if (host.find(':') != std::string::npos) {
        host = "[" + host + "]";
    }
    return "http://" + host + ":" + std::to_string(port()) + "/?token=" + token();
}

void ViewServer::run(bool handleSignals) {
    Impl& d = *impl_;
    if (handleSignals) {
        // Before start: the network thread then owns the signals from its first moment.
        d.signals.emplace(d.ioc, SIGINT, SIGTERM);
        d.signals->async_wait([&d](beast::error_code ec, int signal) {
            if (ec) return;
            d.say(std::string("view: ") + (signal == SIGINT ? "interrupted" : "terminated") +
                  ": shutting down");
            d.requestStop();
        });
    }
    start();
    {
        std::unique_lock lk(d.m);
        d.cv.wait(lk, [&d] { return d.stopping; });
    }
    if (d.renderThread.joinable()) d.renderThread.join();
    d.releaseFollowers();  // data-parallel: the other ranks stop following
    // Close the listening socket and every connection, then let the network thread finish.
    net::post(d.ioc, [&d] {
        beast::error_code ignored;
        d.acceptor.close(ignored);
        d.acceptRetry.cancel();
        if (d.signals) d.signals->cancel(ignored);
        std::lock_guard lk(d.m);
        for (const auto& w : d.sessions)
            if (auto s = w.lock()) s->shutdown();
    });
    // Let the network thread close them, then stop it.
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    d.ioc.stop();
    if (d.ioThread.joinable()) d.ioThread.join();
}

void ViewServer::stop() {
    impl_->requestStop();
}

void ViewServer::follow() {
    Impl& d = *impl_;
    Communicator* comm = d.ranks();
    UVR_CHECK(comm && comm->rank() != 0, "follow() is for the ranks after rank 0");
    for (;;) {
        const std::vector<std::byte> bytes = comm->receiveIdle(0);
        const Json call =
            Json::parse(std::string(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
        const std::string what = call.at("call").get<std::string>();
        if (what == "stop") return;
        // Every failure of a call is rank 0's too (the same data, and agreed where the ranks
        // could differ): rank 0 says it to the page, this rank waits for the next call.
        try {
            if (what == "field") {
                d.field(call.at("spec").get<std::string>(), call.at("step").get<std::size_t>(), {});
            } else if (what == "frame" && d.renderer) {
                ViewState state = d.scene.initial;
                applySet(state, call.at("state"), d.stepCount());
                const auto kind = static_cast<FrameKind>(call.at("kind").get<int>());
                const int scale = kind == FrameKind::Snapshot ? 1 : call.at("scale").get<int>();
                d.renderer->render(frameSettings(state, d.scene.base, scale));
            }
        } catch (const std::exception& e) {
            d.say(std::string("view: this rank's part of a call failed: ") + e.what());
        }
    }
}

}  // namespace uvr::server
