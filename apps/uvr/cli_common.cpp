// SPDX-License-Identifier: MIT
#include "cli_common.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "progress.h"
#include "uvr/core/host_memory.h"
#include "uvr/core/setting_error.h"
#include "uvr/core/text.h"
#include "uvr/cpu/threads.h"

namespace uvr::cli {

namespace {

using Clock = std::chrono::steady_clock;

bool parseFloat(std::string_view s, float& out) {
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    const char* end = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(s.data(), end, out);
    return ec == std::errc() && ptr == end && std::isfinite(out);
}

}  // namespace

void badFlag(const std::string& flag, const std::string& text, const std::string& what) {
    throwError(ErrorKind::Argument, "", flag + " '" + text + "': expected " + what);
}

std::vector<float> parseFloats(const std::string& flag, const std::string& text, std::size_t count,
                               const std::string& what) {
    std::vector<float> out;
    size_t pos = 0;
    while (true) {
        size_t comma = text.find(',', pos);
        float v;
        if (!parseFloat(std::string_view(text).substr(
                            pos, comma == std::string::npos ? std::string::npos : comma - pos),
                        v))
            badFlag(flag, text, what);
        out.push_back(v);
        if (comma == std::string::npos) break;
        pos = comma + 1;
    }
    if (out.size() != count) badFlag(flag, text, what);
    return out;
}

namespace {

/// The long option `name` ("--max-sample-distance") of `app` or of one of its subcommands, or
/// nullptr.
const CLI::Option* findFlag(const CLI::App& app, const std::string& name) {
    if (const CLI::Option* o = app.get_option_no_throw(name)) return o;
    for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
        if (const CLI::Option* o = findFlag(*sub, name)) return o;
    return nullptr;
}

}  // namespace

std::string Context::spell(const std::string& message) const {
    return respellMentions(message, [this](std::string_view setting) {
        std::string flag = "--" + std::string(setting);
        std::replace(flag.begin(), flag.end(), '_', '-');
        if (app && !findFlag(*app, flag) && findFlag(*app, "--no-" + flag.substr(2)))
            flag = "--no-" + flag.substr(2);
        return flag;
    });
}

std::string Context::spell(const Error& error) const {
    const auto* setting = dynamic_cast<const SettingError*>(&error);
    if (!setting) return spell(std::string(error.what()));
    const SettingDef* def = findSetting(setting->setting());
    return spell(
        setting->spelledAs(def ? cliFlag(*def) : spell("`" + setting->setting() + "`"), " "));
}

void Context::step(const std::string& message) const {
    if (!quiet && root()) printStderrLine("uvr: " + printable(spell(message)));
}

void Context::warn(const std::string& message) const {
    if (root()) printStderrLine("uvr: warning: " + printable(spell(message)));
}

void Context::done(const std::string& message, Clock::time_point start) const {
    if (quiet || !root()) return;
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, " (%.2f s)",
                  std::chrono::duration<double>(Clock::now() - start).count());
    printStderrLine("uvr: " + printable(message) + seconds);
}

void Context::setActivity(const std::string& file, const std::string& what) const {
    activityFile_ = file;
    activity_ = what;
}

std::string Context::outOfMemoryMessage() const {
    std::string m = activityFile_.empty() ? "" : activityFile_ + ": ";
    m += "out of memory";
    if (!activity_.empty()) m += " while " + activity_;
    return m;
}

std::string threadsHelp() {
    return "CPU threads: 1 to " + std::to_string(cpu::maxThreadCount()) +
           " (4 per hardware thread, at least 64, at most 1024), or 0 for the default: "
           "OMP_NUM_THREADS when set, else every hardware thread";
}

void applyThreads(int threads) {
    const int cap = cpu::maxThreadCount();
    if (threads < 0 || threads > cap)
        throwError(ErrorKind::Argument, "",
                   "--threads " + std::to_string(threads) + ": expected 1 to " +
                       std::to_string(cap) +
                       " (4 per hardware thread, at least 64, at most "
                       "1024), or 0 for the default");
    if (threads > 0) cpu::setThreadCount(threads);
}

void capEnvironmentThreads() {
    const int cap = cpu::maxThreadCount();
    if (cpu::threadCount() <= cap) return;
    const char* env = std::getenv("OMP_NUM_THREADS");
    std::fprintf(stderr, "uvr: note: OMP_NUM_THREADS=%s is more than %d threads; using %d\n",
                 env ? printableShort(env, 40).c_str() : "?", cap, cap);
    cpu::setThreadCount(cap);
}

std::string jsonText(const nlohmann::json& j) {
    return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::uint64_t parseBytes(const std::string& flag, const std::string& text) {
    std::uint64_t value = 0;
    const char* end = text.data() + text.size();
    auto [ptr, ec] = std::from_chars(text.data(), end, value);
    std::uint64_t scale = 1;
    if (ec == std::errc() && ptr + 1 == end) {
        switch (*ptr) {
            case 'K':
            case 'k':
                scale = 1ull << 10;
                break;
            case 'M':
            case 'm':
                scale = 1ull << 20;
                break;
            case 'G':
            case 'g':
                scale = 1ull << 30;
                break;
            case 'T':
            case 't':
                scale = 1ull << 40;
                break;
            default:
                scale = 0;
        }
        ++ptr;
    }
    if (ec != std::errc() || ptr != end || scale == 0 || value == 0 || value > (~0ull) / scale)
        badFlag(flag, text, "a positive byte count such as 500M or 16G");
    return value * scale;
}

MemoryDefault defaultMaxMemory() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
    const std::uint64_t sysconfBytes =
        pages > 0 && pageSize > 0
            ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(pageSize)
            : 0;
    const HostMemory host = detectHostMemory("/", sysconfBytes);
    if (host.bytes == 0) return {0, "no limit: the physical memory could not be read"};
    auto gib = [](std::uint64_t bytes) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f GiB", double(bytes) / double(1ull << 30));
        return std::string(text);
    };
    const std::uint64_t bytes = host.bytes / 10 * 8;
    return {bytes, gib(bytes) + " = 80% of " + gib(host.bytes) + " (" + host.source + ")"};
}

Vec3f parseVec3(const std::string& flag, const std::string& text) {
    auto v = parseFloats(
        flag, text, 3,
        flag == "--background" ? "three finite numbers r,g,b" : "three finite numbers x,y,z");
    return {v[0], v[1], v[2]};
}

std::pair<float, float> parseRange(const std::string& flag, const std::string& text) {
    auto v = parseFloats(flag, text, 2, "two finite numbers lo,hi with lo <= hi");
    if (v[0] > v[1]) badFlag(flag, text, "two finite numbers lo,hi with lo <= hi");
    return {v[0], v[1]};
}

std::pair<int, int> parseSize(const std::string& flag, const std::string& text) {
    const size_t x = text.find_first_of("xX");
    int w = 0, h = 0;
    auto parseInt = [&](std::string_view s, int& out) {
        auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
        return ec == std::errc() && ptr == s.data() + s.size() && !s.empty();
    };
    if (x == std::string::npos || !parseInt(std::string_view(text).substr(0, x), w) ||
        !parseInt(std::string_view(text).substr(x + 1), h) || w < 1 || h < 1 || w > 16384 ||
        h > 16384)
        badFlag(flag, text, "WIDTHxHEIGHT with each side between 1 and 16384, e.g. 1024x768");
    return {w, h};
}

CudaWarmUp::CudaWarmUp(const std::string& device) {
    if (device != "cpu") startCudaWarmUp();
}

CudaWarmUp::~CudaWarmUp() {
    finishCudaWarmUp();
}

void checkMemoryEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes) {
    if (ctx.maxMemoryBytes == 0 || bytes <= ctx.maxMemoryBytes) return;
    throwError(ErrorKind::Resource, "",
               what + " would need about " + std::to_string(bytes) +
                   " bytes, more than the --max-memory limit of " +
                   std::to_string(ctx.maxMemoryBytes) + " bytes" +
                   (ctx.maxMemoryDefault.empty() ? std::string()
                                                 : " (the default: " + ctx.maxMemoryDefault + ")"));
}

void checkFrameEstimate(const Context& ctx, const std::string& what, std::uint64_t bytes) {
    if (!ctx.maxMemoryDefault.empty() && bytes > kDefaultFrameMemoryBytes)
        throwError(ErrorKind::Resource, "",
                   what + " would need about " + std::to_string(bytes) +
                       " bytes, more than the default limit of image buffers, " +
                       std::to_string(kDefaultFrameMemoryBytes) + " bytes (" +
                       std::to_string(kDefaultFrameMemoryBytes >> 30) +
                       " GiB): give --max-memory to allow a larger frame (e.g. --max-memory " +
                       std::to_string((bytes >> 30) + 1) + "G)");
    checkMemoryEstimate(ctx, what, bytes);
}

void StepFlags::registerOn(CLI::App& app) {
    auto* t = app.add_option("--time", time,
                             "Time step shown at this time (the last step at or before it, as "
                             "ParaView snaps) of a file or series with time steps");
    auto* i = app.add_option("--step-index", index,
                             "Time step by its index (0 is the first) of a file or series with "
                             "time steps");
    t->excludes(i);
}

std::size_t StepFlags::pick(const MeshSeries& series) const {
    if (time) return stepAtTime(series.times(), *time);
    if (index && *index >= series.stepCount())
        throwError(ErrorKind::Argument, series.path(),
                   "--step-index " + std::to_string(*index) + ": the file has " +
                       std::to_string(series.stepCount()) + " time step" +
                       (series.stepCount() == 1 ? "" : "s") + " (0 to " +
                       std::to_string(series.stepCount() - 1) + ")");
    return index.value_or(0);
}

std::unique_ptr<MeshSeries> openSeries(const std::string& path, const Context& ctx,
                                       std::function<void(double)> progress) {
    ReadOptions options;
    options.maxMemoryBytes = ctx.maxMemoryBytes;
    options.progress = std::move(progress);
    return openMeshSeries(path, options);
}

Mesh loadMesh(const std::string& path, const Context& ctx, const StepFlags& steps) {
    ctx.setActivity(path, "reading the mesh");
    Progress progress(ctx, "reading " + path);
    const std::unique_ptr<MeshSeries> series = openSeries(path, ctx, progress.callback());
    const std::size_t step = steps.pick(*series);
    Mesh mesh = series->readStep(step);  // every reader checks the structure it returns
    std::string which;
    if (series->stepCount() > 1) {
        char t[64];
        std::snprintf(t, sizeof t, "%.9g", series->times()[step]);
        which = ", time step " + std::to_string(step) + " of 0-" +
                std::to_string(series->stepCount() - 1) + " (time " + t + ")";
    }
    progress.done("read " + path + which + ": " + std::to_string(mesh.pointCount()) + " points, " +
                  std::to_string(mesh.cellCount()) + " cells");
    if (series->stepCount() > 1 && !steps.time && !steps.index)
        ctx.step("note: " + path + " has " + std::to_string(series->stepCount()) +
                 " time steps; --time or --step-index picks another, `uvr animate` renders all");
    for (const std::string& note : mesh.notes) ctx.step("note: " + note);
    return mesh;
}

SourceSummary checkForRendering(const Mesh& mesh, const ScalarField& field,
                                const std::string& source, const Context& ctx,
                                double* checkSeconds) {
    const auto start = Clock::now();
    ctx.step("checking " + std::to_string(mesh.cellCount()) + " cells and " +
             std::to_string(mesh.pointCount()) + " points");
    ValidationReport report;
    {
        Progress progress(ctx, "checking the mesh");
        report = validateMesh(mesh, source, progress.callback());
    }
    if (checkSeconds) *checkSeconds = std::chrono::duration<double>(Clock::now() - start).count();
    ctx.done("checked the mesh", start);
    SourceSummary summary;
    summary.points = mesh.pointCount();
    summary.cells = mesh.cellCount();
    summary.bounds = report.bounds;
    summary.fieldName = field.name;
    summary.association = field.association;
    summary.fieldChoice = field.choice;
    summary.notes = mesh.notes;
    summary.findings = report.findings();
    for (const std::string& f : summary.findings) ctx.step("validation: " + f);
    if (report.bounds.empty())
        throwError(ErrorKind::Validation, source,
                   mesh.cellCount() == 0
                       ? "the mesh has no volumetric cells: nothing to render"
                       : "no cell has volume: all " + std::to_string(mesh.cellCount()) +
                             " cell(s) are flat (thinner than 1e-7 of their size) or use "
                             "NaN/Inf points; nothing to render");
    return summary;
}

std::string stepKey(const StepFlags& steps) {
    if (steps.time) {
        char t[40];
        std::snprintf(t, sizeof t, "--time %.17g", *steps.time);
        return t;
    }
    if (steps.index) return "--step-index " + std::to_string(*steps.index);
    return "";
}

}  // namespace uvr::cli
