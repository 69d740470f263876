// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/time_series.h"

#include <expat.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/io/exodus.h"
#include "uvr/mesh/io/mesh_merge.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/io/vtk_number.h"
#include "uvr/mesh/io/vtkhdf.h"
#include "uvr/mesh/io/vtu.h"

namespace uvr {

namespace fs = std::filesystem;

MeshSeries::MeshSeries(std::string path, std::vector<double> times, ReadOptions options)
    : path_(std::move(path)), times_(std::move(times)), options_(std::move(options)) {
    UVR_CHECK(!times_.empty(), "a series has at least one step");
}

MeshPart MeshSeries::readPart(std::size_t i, std::uint64_t, std::uint64_t) {
    checkStep(i);
    throwError(ErrorKind::Unsupported, path_, "this format is read whole, not in parts");
}

void MeshSeries::checkStep(std::size_t i) const {
    if (i >= times_.size())
        throwError(ErrorKind::Argument, path_,
                   "no time step " + std::to_string(i) + ": the steps are 0 to " +
                       std::to_string(times_.size() - 1));
}

std::optional<std::vector<Field>> MeshSeries::readFieldsIfSameGeometry(std::size_t i,
                                                                       const MeshView& geometry) {
    Mesh mesh = readStep(i);
    if (!sameGeometry(mesh, geometry)) return std::nullopt;
    return std::move(mesh.fields);
}

bool sameGeometry(const MeshView& a, const MeshView& b) {
    auto same = [](auto x, auto y) {
        return x.size() == y.size() &&
               (x.empty() || std::memcmp(x.data(), y.data(), x.size_bytes()) == 0);
    };
    return same(a.points, b.points) && same(a.cellTypes, b.cellTypes) &&
           same(a.cellOffsets, b.cellOffsets) && same(a.cellIndices, b.cellIndices);
}

bool samePartGeometry(const MeshPart& part, const MeshView& geometry,
                      std::span<const std::uint64_t> pointIds,
                      std::span<const std::uint64_t> cellIds) {
    return std::ranges::equal(part.pointIds, pointIds) &&
           std::ranges::equal(part.cellIds, cellIds) && sameGeometry(part.mesh, geometry);
}

std::size_t stepAtTime(const std::vector<double>& times, double t) {
    if (!std::isfinite(t))
        throw SettingError("time", std::to_string(t), "expected a finite number");
    std::size_t best = 0;
    for (std::size_t i = 0; i < times.size(); ++i)
        if (times[i] <= t && times[i] >= times[best]) best = i;
    return best;
}

namespace {

// ---- One file: a series of one step at time 0 ----

class SingleFileSeries final : public MeshSeries {
public:
    SingleFileSeries(const std::string& path, const ReadOptions& options)
        : MeshSeries(path, {0.0}, options) {}
    Mesh readStep(std::size_t i) override {
        checkStep(i);
        return readMesh(path(), options());
    }
};

// ---- Several files, one (or several parts) per step: .pvd and numbered series ----

/// A step of a file-per-step series: its files (parts merged in order) and, for messages, where
/// the step and each file are listed.
struct FileStep {
    double time = 0;
    std::vector<std::string> files;
    std::string where;
    std::vector<std::string> fileWheres;  // per file: "line 4" (.pvd) or "file NAME" (pattern)
};

/// Reads of a collection's steps now running on this thread: a step that is itself a collection
/// is refused by its format, and this catches one that turns into a collection between that
/// check and its read (unbounded recursion otherwise).
thread_local int stepReadDepth = 0;

class StepReadGuard {
public:
    StepReadGuard(const std::string& series, const std::string& where) {
        if (stepReadDepth > 0)
            throwError(ErrorKind::Parse, series,
                       where +
                           ": a step of a collection or file series is itself one (a "
                           "collection's DataSets are datasets, not collections)");
        ++stepReadDepth;
    }
    ~StepReadGuard() { --stepReadDepth; }
    StepReadGuard(const StepReadGuard&) = delete;
    StepReadGuard& operator=(const StepReadGuard&) = delete;
};

class FileSeries final : public MeshSeries {
public:
    FileSeries(const std::string& path, std::vector<FileStep> steps, const ReadOptions& options)
        : MeshSeries(path, timesOf(steps), options), steps_(std::move(steps)) {}

    std::string stepSource(std::size_t i) const override {
        checkStep(i);
        std::string s;
        for (const std::string& f : steps_[i].files) s += (s.empty() ? "" : ", ") + f;
        return s;
    }

    Mesh readStep(std::size_t i) override {
        checkStep(i);
        const FileStep& step = steps_[i];
        const StepReadGuard guard(path(), step.where);
        for (std::size_t k = 0; k < step.files.size(); ++k) checkStepFile(step, k);
        if (step.files.size() == 1) return readMesh(step.files[0], options());
        Mesh mesh;
        for (std::size_t k = 0; k < step.files.size(); ++k) {
            Mesh part = readMesh(step.files[k], options());
            appendMeshPiece(mesh, part, k == 0, path(), step.where,
                            "part " + std::to_string(k) + " ('" + step.files[k] + "')");
        }
        return mesh;
    }

    /// A step that is one .pvtu (a parallel simulation's output, a .pvd listing one per time) is
    /// stored in its pieces, a step of several files (a .pvd listing a time's parts) in its
    /// files; a step of one other file is read whole.
    const char* partName() const override { return "pieces"; }
    std::uint64_t partCount(std::size_t i) const override {
        checkStep(i);
        const FileStep& step = steps_[i];
        if (step.files.size() > 1) return step.files.size();
        if (sniffMeshFormat(step.files[0]) != MeshFormat::Pvtu) return 0;
        return pvtuPieceCount(step.files[0]);
    }

    MeshPart readPart(std::size_t i, std::uint64_t first, std::uint64_t end) override {
        if (partCount(i) == 0) return MeshSeries::readPart(i, first, end);  // refused there
        const FileStep& step = steps_[i];
        const StepReadGuard guard(path(), step.where);
        if (step.files.size() == 1) return readPvtuPart(step.files[0], first, end, options());
        if (first >= end || end > step.files.size())
            throwError(ErrorKind::Argument, path(),
                       step.where + ": parts [" + std::to_string(first) + ", " +
                           std::to_string(end) + ") asked for, but the step lists " +
                           std::to_string(step.files.size()));
        // The files [first, end) as readStep appends them, with ids in the whole step's order:
        // the file's index above kPieceIdShift bits, the point's or cell's in the file below.
        MeshPart part;
        for (std::uint64_t k = first; k < end; ++k) {
            checkStepFile(step, k);
            Mesh piece = readMesh(step.files[k], options());
            const std::uint64_t base = k << kPieceIdShift;
            for (std::uint64_t p = 0; p < piece.points.size(); ++p)
                part.pointIds.push_back(base | p);
            for (std::uint64_t c = 0; c < piece.cellCount(); ++c) part.cellIds.push_back(base | c);
            appendMeshPiece(part.mesh, piece, k == first, path(), step.where,
                            "part " + std::to_string(k) + " ('" + step.files[k] + "')");
        }
        return part;
    }

private:
    /// Refuses a step's file that is itself a collection (ParaView's collections hold datasets;
    /// one naming another, or itself, would recurse without end).
    void checkStepFile(const FileStep& step, std::size_t k) const {
        const std::string& file = step.files[k];
        if (sniffMeshFormat(file) != MeshFormat::Pvd) return;
        throwError(ErrorKind::Parse, path(),
                   step.fileWheres[k] + ": the step's file " + file +
                       " is itself a ParaView collection (.pvd); a collection's DataSets and a "
                       "series' files must be datasets (.vtu, .pvtu, .vtk, ...), not collections");
    }
    static std::vector<double> timesOf(const std::vector<FileStep>& steps) {
        std::vector<double> t;
        for (const FileStep& s : steps) t.push_back(s.time);
        return t;
    }
    std::vector<FileStep> steps_;
};

struct PvdParse {
    XML_Parser parser = nullptr;
    std::string path;
    fs::path folder;
    bool sawRoot = false, sawCollection = false;
    std::map<double, FileStep> steps;  // by time, parts in listing order
    std::string error;                 // the first error (expat callbacks must not throw)
};

void fail(PvdParse& st, const std::string& message) {
    if (st.error.empty()) st.error = atLine(XML_GetCurrentLineNumber(st.parser)) + ": " + message;
    XML_StopParser(st.parser, XML_FALSE);
}

const char* attr(const XML_Char** attrs, const char* name) {
    for (int i = 0; attrs[i]; i += 2)
        if (std::strcmp(attrs[i], name) == 0) return attrs[i + 1];
    return nullptr;
}

void XMLCALL onPvdStart(void* data, const XML_Char* name, const XML_Char** attrs) {
    auto& st = *static_cast<PvdParse*>(data);
    if (!st.sawRoot) {
        st.sawRoot = true;
        const char* type = attr(attrs, "type");
        if (std::strcmp(name, "VTKFile") != 0 || !type || std::strcmp(type, "Collection") != 0)
            fail(st, "expected <VTKFile type=\"Collection\"> (a ParaView .pvd file)");
        return;
    }
    if (std::strcmp(name, "Collection") == 0) st.sawCollection = true;
    if (std::strcmp(name, "DataSet") != 0) return;
    const char* file = attr(attrs, "file");
    if (!file || !*file) return fail(st, "<DataSet> without a file attribute");
    double time = static_cast<double>(st.steps.size());
    if (const char* t = attr(attrs, "timestep")) {
        const auto v = parseVtkReal(t);
        if (!v || !std::isfinite(*v))
            return fail(st, std::string("<DataSet timestep=\"") + t + "\">: expected a number");
        time = *v;
    }
    if (isSeriesPattern(file))
        return fail(st, std::string("<DataSet file=\"") + file +
                            "\">: a file series pattern ('*'); a collection's DataSets are "
                            "single datasets");
    const fs::path source(file);
    FileStep& step = st.steps[time];
    step.time = time;
    const std::string where = atLine(XML_GetCurrentLineNumber(st.parser));
    if (step.where.empty()) step.where = where;
    step.files.push_back((source.is_absolute() ? source : st.folder / source).string());
    step.fileWheres.push_back(where);
}

std::vector<FileStep> readPvd(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throwError(ErrorKind::Io, path, std::string("cannot open: ") + std::strerror(errno));
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    PvdParse st;
    st.path = path;
    st.folder = fs::path(path).parent_path();
    st.parser = XML_ParserCreate(nullptr);
    UVR_CHECK(st.parser != nullptr, "expat could not create a parser");
    XML_SetUserData(st.parser, &st);
    XML_SetElementHandler(st.parser, onPvdStart, nullptr);
    const bool ok =
        XML_Parse(st.parser, text.data(), static_cast<int>(text.size()), XML_TRUE) == XML_STATUS_OK;
    std::string error = st.error;
    if (!ok && error.empty())
        error = atLine(XML_GetCurrentLineNumber(st.parser)) + ": " +
                XML_ErrorString(XML_GetErrorCode(st.parser));
    XML_ParserFree(st.parser);
    if (!error.empty()) throwError(ErrorKind::Parse, path, error);
    if (!st.sawCollection || st.steps.empty())
        throwError(ErrorKind::Parse, path, "the collection lists no <DataSet file=...>");
    std::vector<FileStep> steps;
    for (auto& [t, s] : st.steps) {
        for (std::size_t k = 0; k < s.files.size(); ++k)
            if (sameFile(s.files[k], path))
                throwError(
                    ErrorKind::Parse, path,
                    s.fileWheres[k] + ": a DataSet names the .pvd itself (" + s.files[k] + ")");
        steps.push_back(std::move(s));
    }
    return steps;
}

/// The files a pattern with one '*' names: the '*' stands for one or more digits; sorted by
/// that number, their times 0, 1, 2, ... (as ParaView's file series). Error(Io) when none exists.
std::vector<FileStep> globNumbered(const std::string& pattern) {
    const fs::path p(pattern);
    const std::string name = p.filename().string();
    const std::size_t star = name.find('*');
    if (star == std::string::npos || name.find('*', star + 1) != std::string::npos ||
        p.parent_path().string().find('*') != std::string::npos)
        throwError(ErrorKind::Argument, pattern,
                   "a file series pattern has one '*', in the file name (e.g. run_*.vtu)");
    const std::string prefix = name.substr(0, star), suffix = name.substr(star + 1);
    const fs::path folder = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    std::error_code ec;
    std::vector<std::pair<std::uint64_t, std::string>> found;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        const std::string n = entry.path().filename().string();
        if (n.size() <= prefix.size() + suffix.size() || n.rfind(prefix, 0) != 0 ||
            n.compare(n.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        const std::string digits =
            n.substr(prefix.size(), n.size() - prefix.size() - suffix.size());
        if (digits.size() > 18 || !std::all_of(digits.begin(), digits.end(),
                                               [](unsigned char c) { return std::isdigit(c); }))
            continue;
        found.emplace_back(std::stoull(digits), (p.parent_path() / n).string());
    }
    if (ec)
        throwError(ErrorKind::Io, pattern,
                   "cannot list the folder " + folder.string() + ": " + ec.message());
    if (found.empty())
        throwError(ErrorKind::Io, pattern,
                   "no file matches (the '*' stands for the step's number: one or more digits)");
    std::sort(found.begin(), found.end());
    std::vector<FileStep> steps;
    for (std::size_t i = 0; i < found.size(); ++i) {
        if (i > 0 && found[i].first == found[i - 1].first)
            throwError(ErrorKind::Argument, pattern,
                       "two files have the number " + std::to_string(found[i].first) + ": " +
                           found[i - 1].second + " and " + found[i].second);
        const std::string where = "file " + found[i].second;
        steps.push_back(FileStep{static_cast<double>(i), {found[i].second}, where, {where}});
    }
    return steps;
}

}  // namespace

bool isSeriesPattern(const std::string& path) {
    return fs::path(path).filename().string().find('*') != std::string::npos;
}

std::unique_ptr<MeshSeries> openMeshSeries(const std::string& path, const ReadOptions& options) {
    if (isSeriesPattern(path))
        return std::make_unique<FileSeries>(path, globNumbered(path), options);
    checkRegularFile(path);
    fileSize(path);  // a missing or unreadable file is named now, not at the first step
    switch (sniffMeshFormat(path)) {  // readMesh's choice, so that the two always agree
        case MeshFormat::Pvd:
            return std::make_unique<FileSeries>(path, readPvd(path), options);
        case MeshFormat::Exodus:
            return openExodus(path, options);
        case MeshFormat::VtkHdf:
            return openVtkHdfSeries(path, options);
        default:
            break;
    }
    return std::make_unique<SingleFileSeries>(path, options);
}

}  // namespace uvr
