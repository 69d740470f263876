// SPDX-License-Identifier: MIT
#include "uvr/mesh/refine.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <span>
#include <type_traits>

#include "uvr/core/error.h"
#include "uvr/core/scratch_vector.h"
#include "uvr/core/setting_error.h"
#include "uvr/mesh/io/native.h"
#include "uvr/mesh/tet_mesh.h"

namespace uvr {

namespace {

/// Items per parallel chunk (fixed, so results never depend on the thread count).
constexpr std::int64_t kChunk = 1 << 14;

/// Local corners of a tetrahedron split into 8: 0-3 the corners, 4-9 the midpoints of edges
/// 01, 02, 03, 12, 13, 23.
constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// The 8 children of a positively oriented tetrahedron for each choice of octahedron diagonal
/// (m01-m23, m02-m13, m03-m12), all positively oriented.
using Children = std::array<std::array<std::uint8_t, 4>, 8>;

/// Derives the child templates on the reference tetrahedron (0,0,0), (2,0,0), (0,2,0), (0,0,2)
/// with exact integer arithmetic; an affine map of positive determinant keeps orientations.
std::array<Children, 3> makeTemplates() {
    int p[10][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 2}};
    for (int e = 0; e < 6; ++e)
        for (int k = 0; k < 3; ++k) p[4 + e][k] = (p[kEdges[e][0]][k] + p[kEdges[e][1]][k]) / 2;
    auto det = [&](const std::array<std::uint8_t, 4>& t) {
        int m[3][3];
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k) m[r][k] = p[t[r + 1]][k] - p[t[0]][k];
        return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    };
    // Opposite midpoints of the octahedron (its three diagonals): edges sharing no corner.
    constexpr int kDiagonals[3][2] = {{4, 9}, {5, 8}, {6, 7}};
    std::array<Children, 3> out{};
    for (int d = 0; d < 3; ++d) {
        Children& c = out[d];
        c[0] = {0, 4, 5, 6};
        c[1] = {4, 1, 7, 8};
        c[2] = {5, 7, 2, 9};
        c[3] = {6, 8, 9, 3};
        // The equator: the other four midpoints in cyclic order (consecutive ones not opposite).
        int equator[4], n = 0;
        for (int o = 0; o < 3; ++o)
            if (o != d) equator[n++] = kDiagonals[o][0];
        for (int o = 0; o < 3; ++o)
            if (o != d) equator[n++] = kDiagonals[o][1];
        // equator = {x0, x1, y0, y1} with x_i opposite y_i: the cycle x0, x1, y0, y1.
        for (int i = 0; i < 4; ++i) {
            std::array<std::uint8_t, 4> t = {static_cast<std::uint8_t>(kDiagonals[d][0]),
                                             static_cast<std::uint8_t>(kDiagonals[d][1]),
                                             static_cast<std::uint8_t>(equator[i]),
                                             static_cast<std::uint8_t>(equator[(i + 1) % 4])};
            if (det(t) < 0) std::swap(t[2], t[3]);
            c[4 + i] = t;
        }
        for (const auto& t : c) UVR_CHECK(det(t) > 0, "refinement template not positive");
    }
    return out;
}

const std::array<Children, 3>& templates() {
    static const std::array<Children, 3> t = makeTemplates();
    return t;
}

/// A tetrahedral mesh being refined: points, tetrahedra and the point fields' values.
struct Work {
    std::vector<Vec3f> points;
    ScratchVector<Tet> tets;
    std::vector<Field> pointFields;
};

/// The unique edges of a tetrahedral mesh, numbered by their smaller vertex, then their larger:
/// the edges a-b (a < b) of vertex a have ids edgeBase[a] to edgeBase[a + 1] - 1, in increasing b
/// (other[id] == b). Ids follow vertex order, so they do not depend on the thread count.
struct EdgeTable {
    ScratchVector<std::uint32_t> other;   ///< the larger vertex of each edge
    std::vector<std::uint64_t> edgeBase;  ///< id of each vertex's first edge; then the count

    std::uint64_t edgeCount() const { return edgeBase.back(); }
    /// Id of edge a-b, a < b.
    std::uint64_t id(std::uint32_t a, std::uint32_t b) const {
        const std::uint32_t* first = other.data() + edgeBase[a];
        const std::uint32_t* last = other.data() + edgeBase[a + 1];
        return edgeBase[a] + std::uint64_t(std::lower_bound(first, last, b) - first);
    }
};

/// Buckets the edges of the tetrahedra by their smaller vertex (counting sort), then sorts each
/// bucket and makes it unique; throws Error(Resource) when the points and midpoints would not fit
/// 32-bit indices.
EdgeTable buildEdges(std::int64_t pointCount, const ScratchVector<Tet>& tets) {
    const std::int64_t tetCount = static_cast<std::int64_t>(tets.size());
    // Bucket sizes (6 edges a tetrahedron, each in the bucket of its smaller vertex).
    std::vector<std::uint64_t> offsets(pointCount + 1, 0);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < tetCount; ++t)
        for (const auto& edge : kEdges) {
            const std::uint32_t a = std::min(tets[t].v[edge[0]], tets[t].v[edge[1]]);
            std::atomic_ref<std::uint64_t>(offsets[a + 1]).fetch_add(1, std::memory_order_relaxed);
        }
    for (std::int64_t p = 0; p < pointCount; ++p) offsets[p + 1] += offsets[p];
    // The buckets, each sorted and made unique in place.
    ScratchVector<std::uint32_t> other(offsets[pointCount]);
    {
        std::vector<std::uint64_t> fill(offsets.begin(), offsets.end() - 1);
#pragma omp parallel for schedule(static)
        for (std::int64_t t = 0; t < tetCount; ++t)
            for (const auto& edge : kEdges) {
                const std::uint32_t a = tets[t].v[edge[0]], b = tets[t].v[edge[1]];
                const std::uint64_t at = std::atomic_ref<std::uint64_t>(fill[std::min(a, b)])
                                             .fetch_add(1, std::memory_order_relaxed);
                other[at] = std::max(a, b);
            }
    }
    EdgeTable e;
    e.edgeBase.assign(pointCount + 1, 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk)
        for (std::int64_t p = start; p < std::min(pointCount, start + kChunk); ++p) {
            std::uint32_t* first = other.data() + offsets[p];
            std::uint32_t* last = other.data() + offsets[p + 1];
            std::sort(first, last);
            e.edgeBase[p + 1] = static_cast<std::uint64_t>(std::unique(first, last) - first);
        }
    for (std::int64_t p = 0; p < pointCount; ++p) e.edgeBase[p + 1] += e.edgeBase[p];
    if (static_cast<std::uint64_t>(pointCount) + e.edgeCount() >= 0xffffffffull)
        throwError(ErrorKind::Resource, "",
                   "refinement would make " + std::to_string(pointCount + e.edgeCount()) +
                       " points (32-bit point indices)");
    // The unique runs packed (about 7 edges for 6 tetrahedra instead of 36 entries).
    e.other.resize(e.edgeCount());
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = 0; start < pointCount; start += kChunk)
        for (std::int64_t p = start; p < std::min(pointCount, start + kChunk); ++p)
            std::copy_n(other.data() + offsets[p], e.edgeBase[p + 1] - e.edgeBase[p],
                        e.other.data() + e.edgeBase[p]);
    return e;
}

/// Values at the midpoints of the edges of vertices [a0, a1) (ids edgeBase[a0] on, written from
/// out[0]), each the mean of its ends' `components` values, in parallel; T is Vec3f (points) or
/// float (a field).
template <typename T>
void edgeMidpoints(const EdgeTable& e, std::int64_t a0, std::int64_t a1, const T* values,
                   int components, T* out) {
    const std::uint64_t base = e.edgeBase[a0];
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t start = a0; start < a1; start += kChunk)
        for (std::int64_t a = start; a < std::min(a1, start + kChunk); ++a)
            for (std::uint64_t id = e.edgeBase[a]; id < e.edgeBase[a + 1]; ++id) {
                const std::uint64_t b = e.other[id];
                T* m = out + (id - base) * components;
                for (int c = 0; c < components; ++c)
                    m[c] = (values[a * components + c] + values[b * components + c]) * 0.5f;
            }
}

/// The 8 children of tetrahedra [t0, t1) (children of t at out[8 (t - t0)] on), in parallel;
/// midpoint ids are pointCount + edge id.
void childTets(const ScratchVector<Tet>& tets, const EdgeTable& e, const Vec3f* points,
               std::uint64_t pointCount, std::int64_t t0, std::int64_t t1, Tet* out) {
    const auto& tmpl = templates();
#pragma omp parallel for schedule(static)
    for (std::int64_t t = t0; t < t1; ++t) {
        std::uint32_t v[10];
        Vec3f mid[10];
        for (int i = 0; i < 4; ++i) v[i] = tets[t].v[i];
        for (int k = 0; k < 6; ++k) {
            const std::uint32_t a = std::min(v[kEdges[k][0]], v[kEdges[k][1]]);
            const std::uint32_t b = std::max(v[kEdges[k][0]], v[kEdges[k][1]]);
            v[4 + k] = static_cast<std::uint32_t>(pointCount + e.id(a, b));
            mid[4 + k] = (points[a] + points[b]) * 0.5f;  // as edgeMidpoints computes it
        }
        // The shortest octahedron diagonal (better shaped children); ties take the first.
        int best = 0;
        double bestLength = INFINITY;
        constexpr int kDiagonals[3][2] = {{4, 9}, {5, 8}, {6, 7}};
        for (int d = 0; d < 3; ++d) {
            const Vec3f p = mid[kDiagonals[d][0]], q = mid[kDiagonals[d][1]];
            const double dx = double(p.x) - q.x, dy = double(p.y) - q.y, dz = double(p.z) - q.z;
            const double length = dx * dx + dy * dy + dz * dz;
            if (length < bestLength) bestLength = length, best = d;
        }
        for (int c = 0; c < 8; ++c)
            for (int i = 0; i < 4; ++i) out[8 * (t - t0) + c].v[i] = v[tmpl[best][c][i]];
    }
}

/// One level of red refinement of `w` in place.
void refineOnce(Work& w) {
    const std::int64_t pointCount = static_cast<std::int64_t>(w.points.size());
    const std::int64_t tetCount = static_cast<std::int64_t>(w.tets.size());
    // Step 1: the edges.
    const EdgeTable e = buildEdges(pointCount, w.tets);
    const std::uint64_t edgeCount = e.edgeCount();
    // Step 2: midpoints and their interpolated point-field values.
    w.points.resize(pointCount + edgeCount);
    edgeMidpoints(e, 0, pointCount, w.points.data(), 1, w.points.data() + pointCount);
    for (Field& f : w.pointFields) {
        f.values.resize((pointCount + edgeCount) * f.components);
        edgeMidpoints(e, 0, pointCount, f.values.data(), f.components,
                      f.values.data() + pointCount * f.components);
    }
    // Step 3: the 8 children of each tetrahedron, in place of children 8t .. 8t+7.
    ScratchVector<Tet> children(static_cast<std::size_t>(8 * tetCount));
    childTets(w.tets, e, w.points.data(), pointCount, 0, tetCount, children.data());
    w.tets = std::move(children);
}

/// "refinement level 2 of 3: 1000 -> 8000 tetrahedra".
std::string levelMessage(int level, int levels, std::uint64_t tets) {
    return "refinement level " + std::to_string(level + 1) + " of " + std::to_string(levels) +
           ": " + std::to_string(tets) + " -> " + std::to_string(8 * tets) + " tetrahedra";
}

/// Values of cell field f for output tetrahedra [t0, t1) (those of the input cell each comes
/// from), in parallel.
void cellFieldValues(const Field& f, const std::vector<std::uint64_t>& sourceCell, int levels,
                     std::int64_t t0, std::int64_t t1, float* out) {
#pragma omp parallel for schedule(static)
    for (std::int64_t t = t0; t < t1; ++t) {
        const std::uint64_t src = sourceCell[static_cast<std::uint64_t>(t) >> (3 * levels)];
        for (int c = 0; c < f.components; ++c)
            out[(t - t0) * f.components + c] = f.values[src * f.components + c];
    }
}

/// Share of the work done: the split makes baseTets, each level 8 times its input, and the output
/// (assembled, or written to a file) takes the last level's tetrahedra once more.
class RefineProgress {
public:
    RefineProgress(const std::function<void(double)>& fraction, int levels)
        : fraction_(fraction), levels_(levels) {}
    /// The total, once the base tetrahedra are known.
    void start(std::uint64_t baseTets) {
        const double outTets = double(refinedTetCount(baseTets, levels_));
        output_ = outTets;
        total_ =
            std::max(1.0, double(baseTets) +
                              outTets * (8.0 / 7.0) * (1.0 - std::pow(8.0, -levels_)) + outTets);
    }
    /// Work done: the tetrahedra a step made.
    void advance(double work) {
        done_ += work;
        report(done_);
    }
    /// A fraction `part` of the last `shares` steps done, each step the output's size (the bytes of
    /// a file written: the file is the whole last level when streamed, shares 2).
    void output(double part, double shares = 1.0) {
        report(total_ - shares * output_ * (1.0 - part));
    }

private:
    void report(double done) {
        if (fraction_) fraction_(std::clamp(done / total_, 0.0, 1.0));
    }
    const std::function<void(double)>& fraction_;
    int levels_;
    double done_ = 0.0, total_ = 1.0, output_ = 0.0;
};

/// The input split into tetrahedra and refined levels - 1 times (the last level is left to the
/// caller), with the input cell of each base tetrahedron; progress as refineMesh says.
struct Prepared {
    Work work;
    std::vector<std::uint64_t> sourceCell;  ///< input cell of each base tetrahedron
    std::uint64_t baseTets = 0;
};

/// Checks levels, splits the cells into tetrahedra and refines them levels - 1 times (of
/// levels >= 1; 0 times for 0); say(message) at each step, progress advanced after each by the
/// tetrahedra it made.
Prepared prepare(const Mesh& mesh, int levels, const std::function<void(const std::string&)>& say,
                 RefineProgress& progress) {
    if (levels < 0 || levels > kMaxRefineLevels)
        throw SettingError("levels", std::to_string(levels),
                           "expected 0 to " + std::to_string(kMaxRefineLevels));
    const std::int64_t cellCount = static_cast<std::int64_t>(mesh.cellCount());
    // Step 1: split cells into tetrahedra (two passes over fixed chunks: count, then fill).
    say("splitting " + std::to_string(cellCount) + " cells into tetrahedra");
    const std::int64_t chunks = (cellCount + kChunk - 1) / kChunk;
    std::vector<std::uint64_t> chunkStart(chunks + 1, 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        std::uint64_t count = 0;
        for (std::int64_t i = c * kChunk; i < std::min(cellCount, (c + 1) * kChunk); ++i)
            count += static_cast<std::uint64_t>(splitCell(mesh, i).count);
        chunkStart[c + 1] = count;
    }
    for (std::int64_t c = 0; c < chunks; ++c) chunkStart[c + 1] += chunkStart[c];
    Prepared p;
    p.baseTets = chunkStart[chunks];
    const std::uint64_t outTets = refinedTetCount(p.baseTets, levels);
    if (outTets > kMaxRefinedTets || (levels > 0 && (outTets >> (3 * levels)) != p.baseTets))
        throwError(ErrorKind::Resource, "",
                   std::to_string(p.baseTets) + " tetrahedra refined " + std::to_string(levels) +
                       " times would exceed " + std::to_string(kMaxRefinedTets) + " tetrahedra");
    progress.start(p.baseTets);
    Work& w = p.work;
    w.points = mesh.points;
    w.tets.resize(p.baseTets);
    p.sourceCell.resize(p.baseTets);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t c = 0; c < chunks; ++c) {
        std::uint64_t at = chunkStart[c];
        for (std::int64_t i = c * kChunk; i < std::min(cellCount, (c + 1) * kChunk); ++i) {
            const CellSplit split = splitCell(mesh, i);
            for (int t = 0; t < split.count; ++t) {
                w.tets[at] = split.tets[t];
                p.sourceCell[at++] = static_cast<std::uint64_t>(i);
            }
        }
    }
    for (const Field& f : mesh.fields)
        if (f.association == Association::Point) w.pointFields.push_back(f);
    progress.advance(double(p.baseTets));
    // Step 2: the refinement levels but the last.
    for (int level = 0; level + 1 < levels; ++level) {
        say(levelMessage(level, levels, w.tets.size()));
        refineOnce(w);
        progress.advance(double(w.tets.size()));
    }
    return p;
}

}  // namespace

std::uint64_t refineMemoryBytes(const Mesh& mesh, std::uint64_t tets, int levels, bool toNative) {
    const std::uint64_t outTets = refinedTetCount(tets, levels);
    std::uint64_t inBytes =
        12 * mesh.pointCount() + 9 * mesh.cellCount() + 4 * mesh.cellIndices.size();
    std::uint64_t pointComps = 0, cellComps = 0;
    for (const Field& f : mesh.fields) {
        inBytes += 4 * f.values.size();
        (f.association == Association::Point ? pointComps : cellComps) += f.components;
    }
    const std::uint64_t outPoints = mesh.pointCount() + outTets / 4;
    if (!toNative || levels == 0)
        return inBytes + outTets * (41 + 4 * cellComps) + outPoints * (12 + 4 * pointComps) +
               8 * tets;
    // Streamed: the last level's input (tetrahedra and the unsorted edge buckets, 16 + 24 bytes
    // each; its points with their fields and 20 bytes of edge tables) and the pieces written
    // (children with their cell fields, midpoints); the levels refined in memory before it need
    // less (about 21 bytes per tetrahedron they make).
    const std::uint64_t lastTets = outTets / 8, lastPoints = mesh.pointCount() + lastTets / 4;
    return inBytes + 8 * tets + lastTets * 40 + lastPoints * (32 + 4 * pointComps) +
           std::min(kRefinePieceTets, lastTets) * (8 * (16 + 4 * cellComps) + 12 + 4 * pointComps);
}

Mesh refineMesh(const Mesh& mesh, int levels,
                const std::function<void(const std::string&)>& progress,
                const std::function<void(double)>& fraction) {
    auto say = [&](const std::string& s) {
        if (progress) progress(s);
    };
    RefineProgress work(fraction, levels);
    Prepared p = prepare(mesh, levels, say, work);
    Work& w = p.work;
    if (levels > 0) {
        say(levelMessage(levels - 1, levels, w.tets.size()));
        refineOnce(w);
        work.advance(double(w.tets.size()));
    }
    // Step 3: the output mesh; cell fields follow the source cell of each tetrahedron.
    say("assembling " + std::to_string(w.tets.size()) + " tetrahedra");
    Mesh out;
    out.points = std::move(w.points);
    const std::int64_t n = static_cast<std::int64_t>(w.tets.size());
    out.cellTypes.assign(n, CellType::Tetra);
    out.cellOffsets.resize(n + 1);
    out.cellIndices.resize(4 * n);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t <= n; ++t) out.cellOffsets[t] = 4 * static_cast<std::uint64_t>(t);
#pragma omp parallel for schedule(static)
    for (std::int64_t t = 0; t < n; ++t)
        for (int i = 0; i < 4; ++i) out.cellIndices[4 * t + i] = w.tets[t].v[i];
    w.tets = {};
    std::size_t nextPointField = 0;
    for (const Field& f : mesh.fields) {
        if (f.association == Association::Point) {
            out.fields.push_back(std::move(w.pointFields[nextPointField++]));
            continue;
        }
        Field g{f.name, f.association, f.components, {}};
        g.values.resize(static_cast<std::size_t>(n) * f.components);
        cellFieldValues(f, p.sourceCell, levels, 0, n, g.values.data());
        out.fields.push_back(std::move(g));
    }
    out.notes = mesh.notes;
    work.output(1.0);
    return out;
}

void refineToNative(const Mesh& mesh, int levels, const std::string& path,
                    const std::function<void(const std::string&)>& progress,
                    const std::function<void(double)>& fraction, std::uint64_t pieceTets) {
    auto say = [&](const std::string& s) {
        if (progress) progress(s);
    };
    RefineProgress work(fraction, levels);
    Prepared p = prepare(mesh, levels, say, work);
    Work& w = p.work;
    const std::int64_t piece = std::int64_t(std::max<std::uint64_t>(pieceTets, 1));
    const std::int64_t pointCount = std::int64_t(w.points.size());
    const std::int64_t tetCount = std::int64_t(w.tets.size());

    // The last level's edges (none with 0 levels: the tetrahedra are written as they are).
    EdgeTable e;
    if (levels > 0) {
        say(levelMessage(levels - 1, levels, w.tets.size()) + ", written to " + path);
        e = buildEdges(pointCount, w.tets);
    }
    const std::uint64_t edgeCount = levels > 0 ? e.edgeCount() : 0;
    const std::uint64_t outPoints = std::uint64_t(pointCount) + edgeCount;
    const std::uint64_t outTets = levels > 0 ? 8 * std::uint64_t(tetCount) : tetCount;
    std::vector<FieldInfo> fields;
    for (const Field& f : mesh.fields) fields.push_back({f.name, f.association, f.components});
    // The last level's work is done as the file is written.
    NativeWriter out(path, outPoints, outTets, 4 * outTets, fields,
                     [&](double part) { work.output(part, levels > 0 ? 2.0 : 1.0); });

    // Points (and later each point field): the old ones, then the midpoints bucket by bucket.
    auto writePointArray = [&](const auto* values, int components, auto&& put) {
        using T = std::remove_cv_t<std::remove_pointer_t<decltype(values)>>;
        put(std::span(values, std::uint64_t(pointCount) * components));
        if (levels == 0) return;
        std::vector<T> mids;
        for (std::int64_t a0 = 0; a0 < pointCount;) {
            std::int64_t a1 = a0 + 1;  // buckets of about `piece` edges
            while (a1 < pointCount && e.edgeBase[a1 + 1] - e.edgeBase[a0] <= std::uint64_t(piece))
                ++a1;
            mids.resize((e.edgeBase[a1] - e.edgeBase[a0]) * components);
            edgeMidpoints(e, a0, a1, values, components, mids.data());
            put(std::span<const T>(mids));
            a0 = a1;
        }
    };
    writePointArray(w.points.data(), 1, [&](std::span<const Vec3f> v) { out.points(v); });

    // Cells: all tetrahedra; the 8 children of each, piece by piece.
    out.tetrahedronTypesAndOffsets();
    static_assert(sizeof(Tet) == 4 * sizeof(std::uint32_t));
    auto indices = [](const Tet* t, std::uint64_t n) {
        return std::span(reinterpret_cast<const std::uint32_t*>(t), 4 * n);
    };
    if (levels == 0) {
        out.cellIndices(indices(w.tets.data(), w.tets.size()));
    } else {
        ScratchVector<Tet> children(8 * std::min(piece, tetCount));
        for (std::int64_t t0 = 0; t0 < tetCount; t0 += piece) {
            const std::int64_t t1 = std::min(tetCount, t0 + piece);
            childTets(w.tets, e, w.points.data(), pointCount, t0, t1, children.data());
            out.cellIndices(indices(children.data(), 8 * (t1 - t0)));
        }
    }

    // Fields in the input's order: point fields interpolated, cell fields copied to children.
    std::size_t nextPointField = 0;
    std::vector<float> values;
    for (const Field& f : mesh.fields) {
        if (f.association == Association::Point) {
            const Field& g = w.pointFields[nextPointField++];
            writePointArray(g.values.data(), g.components,
                            [&](std::span<const float> v) { out.fieldValues(v); });
            continue;
        }
        for (std::int64_t t0 = 0; t0 < std::int64_t(outTets); t0 += 8 * piece) {
            const std::int64_t t1 = std::min<std::int64_t>(outTets, t0 + 8 * piece);
            values.resize(std::uint64_t(t1 - t0) * f.components);
            cellFieldValues(f, p.sourceCell, levels, t0, t1, values.data());
            out.fieldValues(values);
        }
    }
    out.commit();
    work.output(1.0);
}

}  // namespace uvr
