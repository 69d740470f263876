// SPDX-License-Identifier: MIT
#include "uvr/cache/prepared_cache.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <type_traits>

#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"

namespace uvr {

namespace {

/// Bytes before the header: magic, version, reserved, header length, header CRC, reserved.
constexpr std::uint64_t kPreambleBytes = 32;
/// Arrays start at multiples of this offset.
constexpr std::uint64_t kArrayAlignment = 64;
/// Largest header accepted (strings and the array table: far below this).
constexpr std::uint64_t kMaxHeaderBytes = 64ull << 20;
/// Bytes of the source hashed at each end for the fingerprint.
constexpr std::uint64_t kFingerprintBytes = 1ull << 20;
/// Bytes per CRC chunk (hashed in parallel, combined with crc32_combine) and per read or write.
constexpr std::uint64_t kChunkBytes = 32ull << 20;

std::uint64_t alignUp(std::uint64_t v) {
    return (v + kArrayAlignment - 1) / kArrayAlignment * kArrayAlignment;
}

/// CRC32 (zlib's) of bytes, computed over kChunkBytes chunks in parallel and combined.
std::uint32_t parallelCrc(const void* data, std::uint64_t bytes) {
    const auto* p = static_cast<const unsigned char*>(data);
    const std::int64_t chunks = static_cast<std::int64_t>((bytes + kChunkBytes - 1) / kChunkBytes);
    if (chunks <= 1) return static_cast<std::uint32_t>(crc32(0L, p, static_cast<uInt>(bytes)));
    std::vector<uLong> crcs(chunks);
#pragma omp parallel for schedule(dynamic, 1)
    for (std::int64_t i = 0; i < chunks; ++i) {
        const std::uint64_t begin = std::uint64_t(i) * kChunkBytes;
        const std::uint64_t n = std::min(kChunkBytes, bytes - begin);
        crcs[i] = crc32(0L, p + begin, static_cast<uInt>(n));
    }
    uLong crc = crcs[0];
    for (std::int64_t i = 1; i < chunks; ++i) {
        const std::uint64_t begin = std::uint64_t(i) * kChunkBytes;
        crc =
            crc32_combine(crc, crcs[i], static_cast<z_off_t>(std::min(kChunkBytes, bytes - begin)));
    }
    return static_cast<std::uint32_t>(crc);
}

/// Appends plain values and strings to a header.
struct HeaderWriter {
    std::string bytes;
    template <class T>
    void pod(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    void str(const std::string& s) {
        pod(std::uint64_t(s.size()));
        bytes += s;
    }
    void strings(const std::vector<std::string>& list) {
        pod(std::uint64_t(list.size()));
        for (const std::string& s : list) str(s);
    }
    void vec3(Vec3f v) { pod(v.x), pod(v.y), pod(v.z); }
    void bounds(const Bounds3f& b) { vec3(b.lo), vec3(b.hi); }
    void flag(bool b) { pod(std::uint8_t(b ? 1 : 0)); }
};

/// Reads what HeaderWriter wrote, every read checked against the header's end.
struct HeaderReader {
    const std::string& file;
    const std::vector<char>& bytes;
    std::uint64_t pos = 0;

    [[noreturn]] void truncated(const char* what) const {
        throwParseError(file, atByte(kPreambleBytes + pos),
                        std::string("the prepared cache's header ends inside ") + what +
                            " (a damaged or foreign file)");
    }
    template <class T>
    T pod(const char* what = "a number") {
        T v;
        if (bytes.size() - pos < sizeof v) truncated(what);
        std::memcpy(&v, bytes.data() + pos, sizeof v);
        pos += sizeof v;
        return v;
    }
    std::string str(const char* what = "a string") {
        const std::uint64_t n = pod<std::uint64_t>(what);
        if (bytes.size() - pos < n) truncated(what);
        std::string s(bytes.data() + pos, n);
        pos += n;
        return s;
    }
    std::vector<std::string> strings(const char* what) {
        const std::uint64_t n = pod<std::uint64_t>(what);
        if (n > bytes.size() - pos) truncated(what);  // each string takes at least 8 bytes
        std::vector<std::string> out;
        for (std::uint64_t i = 0; i < n; ++i) out.push_back(str(what));
        return out;
    }
    Vec3f vec3() {
        const float x = pod<float>(), y = pod<float>(), z = pod<float>();
        return {x, y, z};
    }
    Bounds3f bounds() {
        Bounds3f b;
        b.lo = vec3();
        b.hi = vec3();
        return b;
    }
    bool flag() { return pod<std::uint8_t>("a flag") != 0; }
};

/// One entry of the array table.
struct ArrayEntry {
    std::string name;
    std::uint64_t elementSize = 0;
    std::uint64_t count = 0;
    std::uint64_t offset = 0;
    std::uint32_t crc = 0;
};

/// Calls f(name, vector) for every array a prepared cache holds, in file order. Mesh is
/// PreparedMesh or const PreparedMesh; the optional parts must be engaged as the header says.
template <class Mesh, class F>
void forEachArray(Mesh& m, F&& f) {
    auto& t = m.tets;
    f("tets.tetCorners", t.tetCorners);
    f("tets.blockVertices", t.blockVertices);
    f("tets.blockVertexBase", t.blockVertexBase);
    // Points and values only where the kernels read them (PreparedMesh::kernelMesh).
    if (t.hasNative()) {
        f("tets.points", t.points);
        f("tets.nativeCorners", t.nativeCorners);
    }
    if (t.hasNative() || t.association == Association::Cell) f("tets.values", t.values);
    f("neighbors.tetCodes", m.neighborCodes.tetCodes);
    f("neighbors.escapes", m.neighborCodes.escapes);
    f("neighbors.escapeBase", m.neighborCodes.escapeBase);
    f("neighbors.native", m.neighborCodes.native);
    f("bvh.nodes", m.bvh.nodes);
    f("bvh.primIds", m.bvh.primIds);
    f("cellTree.nodes", m.cellTree.nodes);
    f("cellTree.primIds", m.cellTree.primIds);
    if (m.kd) {
        f("kd.nodes", m.kd->nodes);
        f("kd.partitions", m.kd->partitions);
        f("gradientSpread", m.gradientSpread);
        f("partitionNan", m.partitionNan);
    }
    if (m.seeds) {
        f("seeds.grids", m.seeds->grids);
        f("seeds.seeds", m.seeds->seeds);
    }
    if (m.macro) {
        f("macro.grids", m.macro->grids);
        f("macro.cells", m.macro->cells);
        f("macro.nanCells", m.macro->nanCells);
    }
}

void writeKey(HeaderWriter& w, const CacheKey& k) {
    w.str(k.sourcePath);
    w.pod(k.sourceSize);
    w.pod(k.sourceMtimeNs);
    w.pod(k.fingerprint);
    w.str(k.fieldSpec);
    w.str(k.step);
    w.flag(k.splitCells), w.flag(k.partitions), w.flag(k.meshBvh), w.flag(k.seedGrids);
    w.flag(k.macroGrids), w.flag(k.forAuto), w.flag(k.autoOnGpu);
    w.pod(k.leafCells);
}

CacheKey readKey(HeaderReader& r) {
    CacheKey k;
    k.sourcePath = r.str("the source path");
    k.sourceSize = r.pod<std::uint64_t>("the source size");
    k.sourceMtimeNs = r.pod<std::int64_t>("the source time");
    k.fingerprint = r.pod<std::uint64_t>("the source fingerprint");
    k.fieldSpec = r.str("the field");
    k.step = r.str("the time step");
    k.splitCells = r.flag(), k.partitions = r.flag(), k.meshBvh = r.flag();
    k.seedGrids = r.flag(), k.macroGrids = r.flag(), k.forAuto = r.flag(), k.autoOnGpu = r.flag();
    k.leafCells = r.pod<std::uint32_t>("the leaf size");
    return k;
}

/// Everything the header holds; the arrays' table last.
struct ParsedHeader {
    CacheHeader header;
    PreparedMesh mesh;  ///< scalars only; kd, seeds, macro engaged as stored
    std::uint64_t tetCount = 0;
    std::vector<ArrayEntry> table;
};

std::string headerBytes(const PreparedMesh& m, const CacheKey& key, const SourceSummary& source,
                        const std::vector<ArrayEntry>& table, const std::string& builder) {
    HeaderWriter w;
    writeKey(w, key);
    // The source's summary.
    w.pod(source.points), w.pod(source.cells);
    w.bounds(source.bounds);
    w.str(source.fieldName);
    w.pod(std::uint8_t(source.association == Association::Cell));
    w.str(source.fieldChoice);
    w.strings(source.notes);
    w.strings(source.findings);
    w.str(builder);
    // TetMesh's scalars.
    const TetMesh& t = m.tets;
    w.pod(std::uint64_t(t.tetCount()));
    w.pod(t.pyramidCount), w.pod(t.wedgeCount), w.pod(t.hexCount);
    w.pod(std::uint8_t(t.association == Association::Cell));
    w.str(t.fieldName);
    w.vec3(t.frame.origin);
    w.pod(t.frame.scale);
    w.bounds(t.bounds);
    w.pod(t.valueMin), w.pod(t.valueMax);
    w.pod(t.totalVolume);
    // PreparedMesh's scalars.
    w.pod(m.sourceCells);
    w.pod(m.splitSeconds), w.pod(m.bvhSeconds), w.pod(m.adjacencySeconds);
    w.flag(m.builtElsewhere);
    w.pod(std::uint64_t(m.phaseSeconds.size()));
    for (const auto& [phase, seconds] : m.phaseSeconds) w.str(phase), w.pod(seconds);
    // The partitions', seed grids' and macrocells' scalars.
    w.flag(m.kd.has_value());
    if (m.kd) {
        w.bounds(m.kd->bounds);
        w.pod(m.kd->leafCells);
        w.pod(m.kd->buildSeconds), w.pod(m.kd->treeSeconds);
    }
    w.flag(m.seeds.has_value());
    if (m.seeds) w.pod(m.seeds->buildSeconds);
    w.flag(m.macro.has_value());
    if (m.macro) w.pod(m.macro->buildSeconds);
    // The array table.
    w.pod(std::uint64_t(table.size()));
    for (const ArrayEntry& e : table) {
        w.str(e.name);
        w.pod(e.elementSize), w.pod(e.count), w.pod(e.offset), w.pod(e.crc);
    }
    return w.bytes;
}

/// A prepared cache is code-like input (its arrays steer the kernels), so only a file that the
/// current user owns and that nobody else can write is trusted: another user could have planted
/// it (its checksums prove nothing against a deliberate writer). Throws Error(Io) saying why.
void checkTrusted(const std::string& path, const struct stat& st) {
    if (st.st_uid != ::geteuid())
        throwError(ErrorKind::Io, path,
                   "not trusted as a prepared cache: it belongs to " + describeUser(st.st_uid) +
                       ", not to the current user " + describeUser(::geteuid()));
    if (st.st_mode & (S_IWGRP | S_IWOTH)) {
        char mode[8];
        std::snprintf(mode, sizeof mode, "%04o", unsigned(st.st_mode & 07777));
        throwError(ErrorKind::Io, path,
                   std::string("not trusted as a prepared cache: its group or other users may "
                               "write it (mode ") +
                       mode + ")");
    }
}

/// A file opened for reading, closed on scope exit.
struct InputFile {
    std::FILE* f = nullptr;
    std::string path;
    std::uint64_t size = 0;

    /// Opens p, refusing anything but a regular file before it could block (a FIFO opened
    /// for reading waits for a writer); a cache must also be trusted (checkTrusted).
    InputFile(const std::string& p, bool cache) : path(p) {
        const int fd = ::open(p.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
        if (fd < 0)
            throwError(ErrorKind::Io, p, std::string("cannot open: ") + std::strerror(errno));
        struct stat st;
        if (::fstat(fd, &st) != 0) {
            const int err = errno;
            ::close(fd);
            throwError(ErrorKind::Io, p, std::string("cannot stat: ") + std::strerror(err));
        }
        if (!S_ISREG(st.st_mode)) {
            ::close(fd);
            throwError(ErrorKind::Io, p,
                       std::string("not a regular file (") + describeFileType(st.st_mode) + ")" +
                           (cache ? ": a prepared cache must be a file" : ""));
        }
        if (cache) {
            try {
                checkTrusted(p, st);
            } catch (...) {
                ::close(fd);
                throw;
            }
        }
        ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
        f = ::fdopen(fd, "rb");
        if (!f) {
            const int err = errno;
            ::close(fd);
            throwError(ErrorKind::Io, p, std::string("cannot open: ") + std::strerror(err));
        }
        size = static_cast<std::uint64_t>(st.st_size);
    }
    ~InputFile() { std::fclose(f); }
    InputFile(const InputFile&) = delete;
    InputFile& operator=(const InputFile&) = delete;

    /// Reads bytes at offset (checked against the size before the call) in large chunks.
    void read(std::uint64_t offset, void* out, std::uint64_t bytes, const char* what,
              const std::function<void(std::uint64_t)>& advanced = {}) {
        if (fseeko(f, static_cast<off_t>(offset), SEEK_SET) != 0)
            throwError(ErrorKind::Io, path, std::string("cannot seek to ") + what);
        auto* p = static_cast<char*>(out);
        for (std::uint64_t done = 0; done < bytes;) {
            const std::uint64_t n = std::min(kChunkBytes, bytes - done);
            if (std::fread(p + done, 1, n, f) != n)
                throwError(ErrorKind::Io, path,
                           std::string("reading ") + what + " failed at " + atByte(offset + done) +
                               ": " +
                               (std::ferror(f) ? std::strerror(errno) : "unexpected end of file"));
            done += n;
            if (advanced) advanced(n);
        }
    }
};

/// True when every coordinate is finite (an empty box keeps its finite +-FLT_MAX corners).
bool finite(Vec3f v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const Bounds3f& b) {
    return finite(b.lo) && finite(b.hi);
}

/// The header's counts and geometry, checked as a mesh's would be (a crafted file's header CRC
/// matches whatever it says): cell counts within 32-bit cell ids (so the arrays' expected
/// lengths cannot overflow), bounds and the frame finite, the scale positive.
void checkHeaderScalars(const ParsedHeader& h, const std::string& path) {
    const TetMesh& t = h.mesh.tets;
    const auto bad = [&](const std::string& what) {
        throwError(
            ErrorKind::Parse, path,
            "the prepared cache's header is invalid: " + what + " (a damaged or crafted file)");
    };
    const std::uint64_t counts[4] = {h.tetCount, t.pyramidCount, t.wedgeCount, t.hexCount};
    std::uint64_t cells = 0;
    for (std::uint64_t c : counts) {
        if (c >= kNoTet) bad("a cell count of " + std::to_string(c) + " (at most 2^32 - 2)");
        cells += c;
    }
    if (cells >= kNoTet) bad(std::to_string(cells) + " cells (at most 2^32 - 2)");
    if (!finite(h.header.source.bounds) || !finite(t.bounds) || !finite(t.frame.origin) ||
        (h.mesh.kd && !finite(h.mesh.kd->bounds)))
        bad("bounds that are not finite");
    if ((h.mesh.seeds || h.mesh.macro) && !h.mesh.kd) bad("grids without k-d partitions");
    if (!(std::isfinite(t.frame.scale) && t.frame.scale > 0.0))
        bad("the frame's scale is " + std::to_string(t.frame.scale));
}

ParsedHeader parseHeader(InputFile& in) {
    const std::string& path = in.path;
    if (in.size < kPreambleBytes)
        throwParseError(path, atByte(in.size),
                        "not a prepared cache: " + std::to_string(in.size) +
                            " bytes, shorter than its " + std::to_string(kPreambleBytes) +
                            "-byte preamble (truncated?)");
    unsigned char pre[kPreambleBytes];
    in.read(0, pre, kPreambleBytes, "the preamble");
    if (std::memcmp(pre, kPreparedCacheMagic, 8) != 0)
        throwParseError(path, atByte(0),
                        "not a prepared cache (its first bytes are not \"UVRPREP\"); prepare one "
                        "with `uvr prepare MESH`");
    std::uint32_t version, headerCrc;
    std::uint64_t headerLength;
    std::memcpy(&version, pre + 8, 4);
    std::memcpy(&headerLength, pre + 16, 8);
    std::memcpy(&headerCrc, pre + 24, 4);
    if (version != kPreparedCacheVersion)
        throwParseError(path, atByte(8),
                        "prepared cache format version " + std::to_string(version) +
                            ", this uvr reads version " + std::to_string(kPreparedCacheVersion) +
                            " only: prepare it again with this uvr (`uvr prepare MESH`)");
    if (headerLength > kMaxHeaderBytes || headerLength > in.size - kPreambleBytes)
        throwParseError(path, atByte(16),
                        "header of " + std::to_string(headerLength) + " bytes, but the file has " +
                            std::to_string(in.size - kPreambleBytes) +
                            " after the preamble (truncated or damaged)");
    std::vector<char> bytes(headerLength);
    in.read(kPreambleBytes, bytes.data(), headerLength, "the header");
    if (parallelCrc(bytes.data(), headerLength) != headerCrc)
        throwParseError(path, atByte(kPreambleBytes),
                        "the header's CRC32 does not match (the file is damaged)");

    HeaderReader r{path, bytes};
    ParsedHeader out;
    CacheHeader& h = out.header;
    h.key = readKey(r);
    SourceSummary& s = h.source;
    s.points = r.pod<std::uint64_t>(), s.cells = r.pod<std::uint64_t>();
    s.bounds = r.bounds();
    s.fieldName = r.str("the field name");
    s.association = r.pod<std::uint8_t>() ? Association::Cell : Association::Point;
    s.fieldChoice = r.str();
    s.notes = r.strings("the notes");
    s.findings = r.strings("the validation findings");
    h.builderDevice = r.str();
    PreparedMesh& m = out.mesh;
    TetMesh& t = m.tets;
    out.tetCount = r.pod<std::uint64_t>("the tetrahedron count");
    t.pyramidCount = r.pod<std::uint64_t>(), t.wedgeCount = r.pod<std::uint64_t>();
    t.hexCount = r.pod<std::uint64_t>();
    t.association = r.pod<std::uint8_t>() ? Association::Cell : Association::Point;
    t.fieldName = r.str();
    t.frame.origin = r.vec3();
    t.frame.scale = r.pod<double>();
    t.bounds = r.bounds();
    t.valueMin = r.pod<float>(), t.valueMax = r.pod<float>();
    t.totalVolume = r.pod<double>();
    m.sourceCells = r.pod<std::uint64_t>();
    m.splitSeconds = r.pod<double>(), m.bvhSeconds = r.pod<double>();
    m.adjacencySeconds = r.pod<double>();
    m.builtElsewhere = r.flag();
    const std::uint64_t phases = r.pod<std::uint64_t>("the phase count");
    if (phases > bytes.size()) r.truncated("the phases");
    for (std::uint64_t i = 0; i < phases; ++i) {
        std::string name = r.str("a phase");
        m.phaseSeconds.emplace_back(std::move(name), r.pod<double>("a phase"));
    }
    if (r.flag()) {
        m.kd.emplace();
        m.kd->bounds = r.bounds();
        m.kd->leafCells = r.pod<std::uint32_t>();
        m.kd->buildSeconds = r.pod<double>(), m.kd->treeSeconds = r.pod<double>();
    }
    if (r.flag()) m.seeds.emplace().buildSeconds = r.pod<double>();
    if (r.flag()) m.macro.emplace().buildSeconds = r.pod<double>();
    const std::uint64_t arrays = r.pod<std::uint64_t>("the array count");
    if (arrays > bytes.size()) r.truncated("the array table");
    for (std::uint64_t i = 0; i < arrays; ++i) {
        ArrayEntry e;
        e.name = r.str("the array table");
        e.elementSize = r.pod<std::uint64_t>("the array table");
        e.count = r.pod<std::uint64_t>("the array table");
        e.offset = r.pod<std::uint64_t>("the array table");
        e.crc = r.pod<std::uint32_t>("the array table");
        // Element sizes are those of the structs (at most a BVH node's 32 bytes); a count
        // must fit the file (so the byte count below cannot overflow).
        if (e.elementSize == 0 || e.elementSize > 1024 || e.count > in.size / e.elementSize)
            throwParseError(path, atByte(kPreambleBytes + r.pos),
                            "array '" + e.name + "' of " + std::to_string(e.count) +
                                " elements of " + std::to_string(e.elementSize) +
                                " bytes does not fit the file's " + std::to_string(in.size) +
                                " bytes (a damaged or crafted file)");
        out.table.push_back(std::move(e));
    }
    checkHeaderScalars(out, path);
    h.cells = out.tetCount + t.pyramidCount + t.wedgeCount + t.hexCount;
    for (const ArrayEntry& e : out.table) h.arrayBytes += e.elementSize * e.count;
    return out;
}

std::string mib(std::uint64_t bytes) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / 1048576.0);
    return buf;
}

/// Throws Error(Parse) "FILE: the prepared cache is inconsistent: WHAT" unless ok.
void expect(bool ok, const std::string& path, const std::string& what) {
    if (!ok) throwError(ErrorKind::Parse, path, "the prepared cache is inconsistent: " + what);
}

/// True when a binary tree of `count` nodes whose inner nodes keep their children at c, c + 1 is
/// well formed: from the root (at depth rootDepth), no node is reached twice (no cycles), no inner
/// node sits at maxDepth or deeper (a traversal's stack) and every leaf passes leafOk(i).
/// firstChild(i) is node i's first child, or nothing for a leaf.
template <class FirstChild, class LeafOk>
bool treeWellFormed(std::size_t count, int rootDepth, int maxDepth, FirstChild firstChild,
                    LeafOk leafOk) {
    std::vector<std::uint8_t> seen(count, 0);
    std::vector<std::pair<std::uint32_t, int>> stack{{0u, rootDepth}};
    while (!stack.empty()) {
        const auto [i, depth] = stack.back();
        stack.pop_back();
        if (seen[i]) return false;
        seen[i] = 1;
        const std::optional<std::uint32_t> child = firstChild(i);
        if (!child) {
            if (!leafOk(i)) return false;
            continue;
        }
        if (depth >= maxDepth || std::uint64_t(*child) + 1 >= count) return false;
        stack.push_back({*child, depth + 1});
        stack.push_back({*child + 1, depth + 1});
    }
    return true;
}

/// treeWellFormed for a BVH whose leaves lie within `prims` entries.
bool bvhWellFormed(const std::vector<BvhNode>& nodes, std::uint64_t prims) {
    if (nodes.empty()) return true;
    return treeWellFormed(
        nodes.size(), 1, kBvhMaxDepth,
        [&](std::uint32_t i) {
            return nodes[i].count > 0 ? std::nullopt : std::optional<std::uint32_t>(nodes[i].first);
        },
        [&](std::uint32_t i) { return std::uint64_t(nodes[i].first) + nodes[i].count <= prims; });
}

/// treeWellFormed for the k-d tree, whose leaves name partitions.
bool kdWellFormed(const std::vector<KdNode>& nodes, std::uint64_t partitions) {
    if (nodes.empty()) return partitions == 0;
    return treeWellFormed(
        nodes.size(), 0, kKdMaxDepth,
        [&](std::uint32_t i) {
            return nodes[i].isLeaf() ? std::nullopt
                                     : std::optional<std::uint32_t>(nodes[i].child());
        },
        [&](std::uint32_t i) { return nodes[i].child() < partitions; });
}

/// True when every id is a cell or kNoTet.
bool cellIds(const std::uint32_t* ids, std::uint64_t n, std::uint64_t cells) {
    std::uint64_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad)
    for (std::int64_t i = 0; i < std::int64_t(n); ++i) bad += ids[i] != kNoTet && ids[i] >= cells;
    return bad == 0;
}

/// Why grids laid out as layoutPartitionGrids does are not, over an array of `cells` entries
/// (empty when they are): every side 1 to kMaxGridSide (cellIndex clamps to dims - 1), each
/// grid's cells right after the previous grid's, all of them exactly the array and within
/// 32-bit indices (the kernels' index arithmetic), origin finite, cells per unit not negative.
std::string gridsMalformed(const std::vector<PartitionGrid>& grids, std::uint64_t cells) {
    std::uint64_t total = 0;
    for (std::size_t p = 0; p < grids.size(); ++p) {
        const PartitionGrid& g = grids[p];
        const std::string which = "grid " + std::to_string(p);
        for (int a = 0; a < 3; ++a) {
            if (g.dims[a] < 1 || g.dims[a] > kMaxGridSide)
                return which + " has " + std::to_string(g.dims[a]) + " cells on axis " +
                       std::to_string(a) + " (1 to " + std::to_string(kMaxGridSide) + ")";
            if (std::isnan(g.cellsPerUnit[a]) || g.cellsPerUnit[a] < 0.f)
                return which + " has a negative or NaN cell size";
        }
        if (!finite(g.lo)) return which + " has an origin that is not finite";
        if (g.first != total)
            return which + " starts at cell " + std::to_string(g.first) +
                   ", not right after the "
                   "previous grid (" +
                   std::to_string(total) + ")";
        total += std::uint64_t(g.dims[0]) * g.dims[1] * g.dims[2];
        if (total >= 0xffffffffull) return "the grids' cells exceed 32-bit indices";
    }
    if (total != cells)
        return "the grids hold " + std::to_string(total) + " cells, the array " +
               std::to_string(cells);
    return "";
}

/// Every index the kernels follow lies in range: corners in their block, neighbour codes, escapes
/// and ids, trees, grids (a crafted file whose CRCs match must not send a kernel out of bounds).
void checkIndices(const PreparedMesh& m, std::uint64_t tetCount, const std::string& path) {
    const TetMesh& t = m.tets;
    const CompactNeighbors& nb = m.neighborCodes;
    const std::uint64_t cells = tetCount + t.pyramidCount + t.wedgeCount + t.hexCount;
    const std::uint64_t blocks = (tetCount + kTetBlockSize - 1) / kTetBlockSize;
    expect(tetCount == 0 || nb.escapeBase.size() == blocks + 1, path,
           "neighbors.escapeBase does not hold one entry per block and one more");
    std::uint64_t badCorners = 0, badCodes = 0;
#pragma omp parallel for schedule(static) reduction(+ : badCorners, badCodes)
    for (std::int64_t i = 0; i < std::int64_t(tetCount); ++i) {
        const std::uint64_t b = std::uint64_t(i) >> kTetBlockBits;
        const std::uint32_t vertices = t.blockVertexBase[b + 1] - t.blockVertexBase[b];
        const std::uint32_t escapes = nb.escapeBase[b + 1] - nb.escapeBase[b];
        for (int k = 0; k < 4; ++k) {
            badCorners += t.tetCorners[i].v[k] >= vertices;
            const std::uint32_t code = nb.tetCodes[i].c[k];
            if (code < kTetBlockSize)
                badCodes +=
                    ((std::uint64_t(i) & ~std::uint64_t(kTetBlockSize - 1)) | code) >= tetCount;
            else if (code != kNoNeighborCode)
                badCodes += code - kTetBlockSize >= escapes;
        }
    }
    expect(badCorners == 0, path, "a tetrahedron's corner lies outside its block");
    expect(badCodes == 0, path, "a tetrahedron's neighbour code lies outside its block");
    expect(cellIds(nb.escapes.data(), nb.escapes.size(), cells) &&
               cellIds(nb.native.data(), nb.native.size(), cells),
           path, "a face neighbour is not a cell");
    // The cell tree's leaves are cell ranges (buildCellTree), or name cells through primIds.
    const Bvh& tree = m.cellTree;
    expect(tree.primIds.empty() ? bvhWellFormed(tree.nodes, cells)
                                : bvhWellFormed(tree.nodes, tree.primIds.size()) &&
                                      cellIds(tree.primIds.data(), tree.primIds.size(), cells) &&
                                      std::find(tree.primIds.begin(), tree.primIds.end(), kNoTet) ==
                                          tree.primIds.end(),
           path, "the cell tree is malformed");
    expect(bvhWellFormed(m.bvh.nodes, m.bvh.primIds.size()) &&
               cellIds(m.bvh.primIds.data(), m.bvh.primIds.size(), cells) &&
               std::find(m.bvh.primIds.begin(), m.bvh.primIds.end(), kNoTet) == m.bvh.primIds.end(),
           path, "the mesh BVH is malformed");
    if (m.kd) {
        expect(kdWellFormed(m.kd->nodes, m.kd->partitions.size()), path,
               "the k-d tree is malformed");
        if (m.seeds)
            expect(cellIds(m.seeds->seeds.data(), m.seeds->seeds.size(), cells), path,
                   "a seed is not a cell");
    }
}

/// The counts the arrays must agree on (a damaged or crafted file whose CRCs match).
void checkConsistent(const PreparedMesh& m, std::uint64_t tetCount, const std::string& path) {
    const TetMesh& t = m.tets;
    const std::uint64_t blocks = (tetCount + kTetBlockSize - 1) / kTetBlockSize;
    expect(t.tetCorners.size() == tetCount, path,
           "tets.tetCorners does not hold one entry per tetrahedron");
    expect(tetCount == 0 ? t.blockVertexBase.size() <= 1 : t.blockVertexBase.size() == blocks + 1,
           path, "tets.blockVertexBase does not hold one entry per block and one more");
    for (std::size_t b = 0; b + 1 < t.blockVertexBase.size(); ++b)
        expect(t.blockVertexBase[b] <= t.blockVertexBase[b + 1] &&
                   t.blockVertexBase[b + 1] - t.blockVertexBase[b] <= 4 * kTetBlockSize,
               path, "tets.blockVertexBase is not increasing");
    expect(t.blockVertexBase.empty() || t.blockVertexBase.back() == t.blockVertices.size(), path,
           "tets.blockVertexBase does not end at the block vertices' count");
    const std::uint64_t nativeCorners = 5 * t.pyramidCount + 6 * t.wedgeCount + 8 * t.hexCount;
    expect(t.nativeCorners.size() == (t.hasNative() ? nativeCorners : 0), path,
           "tets.nativeCorners does not hold the native cells' corners");
    for (std::uint32_t id : t.nativeCorners)
        expect(id < t.points.size(), path, "a native cell's corner is not a point");
    if (t.hasNative() || t.association == Association::Cell) {
        const std::uint64_t cells = tetCount + t.pyramidCount + t.wedgeCount + t.hexCount;
        expect(t.values.size() == (t.association == Association::Cell ? cells : t.points.size()),
               path, "tets.values does not hold one value per point or cell");
    }
    expect(m.neighborCodes.tetCodes.size() == tetCount, path,
           "neighbors.tetCodes does not hold one entry per tetrahedron");
    expect(m.neighborCodes.escapeBase.size() == (tetCount ? blocks + 1 : 0) ||
               m.neighborCodes.escapeBase.size() <= 1,
           path, "neighbors.escapeBase does not hold one entry per block and one more");
    if (!m.neighborCodes.escapeBase.empty())
        expect(m.neighborCodes.escapeBase.back() == m.neighborCodes.escapes.size(), path,
               "neighbors.escapeBase does not end at the escapes' count");
    const std::vector<std::uint32_t>& eb = m.neighborCodes.escapeBase;
    for (std::size_t b = 0; b + 1 < eb.size(); ++b)
        expect(eb[b] <= eb[b + 1], path, "neighbors.escapeBase is not increasing");
    expect(m.neighborCodes.native.size() == 5 * (t.pyramidCount + t.wedgeCount) + 6 * t.hexCount,
           path, "neighbors.native does not hold one entry per native face");
    if (m.kd) {
        const std::size_t n = m.kd->partitions.size();
        expect(m.gradientSpread.size() == n, path, "gradientSpread is not one per partition");
        expect(m.partitionNan.empty() || m.partitionNan.size() == n, path,
               "partitionNan is not one per partition");
        for (const KdPartition& part : m.kd->partitions)
            expect(finite(part.box), path, "a partition's box is not finite");
        if (m.seeds) {
            expect(m.seeds->grids.size() == n, path, "the seed grids do not match the partitions");
            const std::string why = gridsMalformed(m.seeds->grids, m.seeds->seeds.size());
            expect(why.empty(), path, "the seed grids are malformed: " + why);
        }
        if (m.macro) {
            expect(m.macro->grids.size() == n, path,
                   "the macrocell grids do not match the partitions");
            const std::string why = gridsMalformed(m.macro->grids, m.macro->cells.size());
            expect(why.empty(), path, "the macrocell grids are malformed: " + why);
            expect(m.macro->nanCells.empty() || m.macro->nanCells.size() == m.macro->cells.size(),
                   path, "macro.nanCells is not one per macrocell");
        }
    }
}

}  // namespace

StaleCacheError::StaleCacheError(const std::string& file, const std::string& reason)
    : Error(ErrorKind::Argument,
            (file.empty() ? "" : file + ": ") + "the prepared cache does not match: " + reason),
      reason_(reason) {}

CacheKey makeCacheKey(const std::string& meshPath, const std::string& fieldSpec,
                      const std::string& step, const PrepareOptions& options) {
    CacheKey k;
    std::error_code ec;
    const std::filesystem::path canonical = std::filesystem::canonical(meshPath, ec);
    if (ec) throwError(ErrorKind::Io, meshPath, "cannot resolve the path: " + ec.message());
    k.sourcePath = canonical.string();
    {
        InputFile in(k.sourcePath, false);
        struct stat st;
        if (stat(k.sourcePath.c_str(), &st) != 0)
            throwError(ErrorKind::Io, meshPath,
                       std::string("cannot stat: ") + std::strerror(errno));
        k.sourceSize = in.size;
        k.sourceMtimeNs = std::int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
        // Fingerprint: the first and the last MiB (the whole file when smaller).
        const std::uint64_t n = std::min(kFingerprintBytes, in.size);
        std::vector<char> buf(n);
        in.read(0, buf.data(), n, "the first MiB");
        const std::uint64_t first = parallelCrc(buf.data(), n);
        in.read(in.size - n, buf.data(), n, "the last MiB");
        k.fingerprint = (first << 32) | parallelCrc(buf.data(), n);
    }
    k.fieldSpec = fieldSpec;
    k.step = step;
    k.splitCells = options.cells.splitCells;
    k.partitions = options.partitions;
    k.meshBvh = options.meshBvh;
    k.forAuto = options.forAuto;
    k.autoOnGpu = options.forAuto && options.autoOnGpu;
    k.seedGrids = options.seedGrids;
    k.macroGrids = options.macroGrids;
    k.leafCells = options.kd.leafCells;
    return k;
}

std::string cacheKeyMismatch(const CacheKey& s, const CacheKey& e) {
    const auto yesNo = [](bool b) { return std::string(b ? "with" : "without"); };
    const auto quoted = [](const std::string& v, const char* none) {
        return v.empty() ? std::string(none) : "'" + v + "'";
    };
    if (s.sourcePath != e.sourcePath)
        return "it was prepared from " + s.sourcePath + ", not " + e.sourcePath;
    if (s.sourceSize != e.sourceSize)
        return "the mesh changed since the cache was prepared (" + std::to_string(s.sourceSize) +
               " bytes then, " + std::to_string(e.sourceSize) + " now)";
    if (s.sourceMtimeNs != e.sourceMtimeNs)
        return "the mesh changed since the cache was prepared (its modification time differs)";
    if (s.fingerprint != e.fingerprint)
        return "the mesh changed since the cache was prepared (its first or last MiB differ)";
    if (s.fieldSpec != e.fieldSpec)
        return "it was prepared for `field` " + quoted(s.fieldSpec, "(the default)") +
               ", this asks for " + quoted(e.fieldSpec, "the default field");
    if (s.step != e.step)
        return "it was prepared for the time step " + quoted(s.step, "(the first)") +
               ", this asks for " + quoted(e.step, "the first");
    if (s.splitCells != e.splitCells)
        return "it was prepared " + yesNo(s.splitCells) + " `split_cells`, this asks " +
               yesNo(e.splitCells);
    if (s.partitions != e.partitions || s.meshBvh != e.meshBvh || s.forAuto != e.forAuto) {
        const auto method = [](const CacheKey& k) {
            std::string what =
                k.partitions ? "partitions (`method` adaptive)" : std::string("no partitions");
            if (k.meshBvh) what += " and the mesh BVH (`method` reference/exact)";
            if (k.forAuto) what += " and what `method` auto renders with";
            return what;
        };
        return "it holds " + method(s) + ", this needs " + method(e);
    }
    if (s.autoOnGpu != e.autoOnGpu)
        return std::string("it holds what `method` auto renders with on the ") +
               (s.autoOnGpu ? "GPU" : "CPU") + ", this renders on the " +
               (e.autoOnGpu ? "GPU" : "CPU");
    if ((s.partitions || s.forAuto) && s.leafCells != e.leafCells)
        return "its partitions hold up to " + std::to_string(s.leafCells) +
               " cells (`leaf_cells`), this asks for " + std::to_string(e.leafCells) +
               " (the default differs between `device` cpu and cuda)";
    if ((s.partitions || s.forAuto) && s.seedGrids != e.seedGrids)
        return "it was prepared " + yesNo(s.seedGrids) + " seed grids, this asks " +
               yesNo(e.seedGrids) + " (`seed_grid`)";
    if (s.partitions && s.macroGrids != e.macroGrids)
        return "it was prepared " + yesNo(s.macroGrids) + " macrocell grids, this asks " +
               yesNo(e.macroGrids);
    return "";
}

std::uint64_t writePreparedCache(const PreparedMesh& mesh, const CacheKey& key,
                                 const SourceSummary& source, const std::string& path,
                                 const std::function<void(double)>& progress) {
    // The table: offsets after the header (whose length depends on the table's strings only, so
    // a first pass with zero offsets sizes it) and CRCs.
    struct Source {
        const void* data;
        std::uint64_t bytes;
    };
    std::vector<ArrayEntry> table;
    std::vector<Source> sources;
    forEachArray(mesh, [&](const char* name, const auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        table.push_back(
            {name, sizeof(T), v.size(), 0, parallelCrc(v.data(), v.size() * sizeof(T))});
        sources.push_back({v.data(), v.size() * sizeof(T)});
    });
    const std::string builder = mesh.builtElsewhere ? "the GPU" : "cpu";
    const std::uint64_t headerLength = headerBytes(mesh, key, source, table, builder).size();
    std::uint64_t offset = alignUp(kPreambleBytes + headerLength), total = 0;
    for (std::size_t i = 0; i < table.size(); ++i) {
        table[i].offset = offset;
        offset = alignUp(offset + sources[i].bytes);
        total += sources[i].bytes;
    }
    const std::string header = headerBytes(mesh, key, source, table, builder);
    UVR_CHECK(header.size() == headerLength, "the prepared cache's header changed length");

    OutputFile out(path);
    out.denyOthersWrite();  // a reader trusts no cache that others may write
    unsigned char pre[kPreambleBytes] = {};
    std::memcpy(pre, kPreparedCacheMagic, 8);
    const std::uint32_t version = kPreparedCacheVersion;
    const std::uint32_t headerCrc = parallelCrc(header.data(), header.size());
    std::memcpy(pre + 8, &version, 4);
    std::memcpy(pre + 16, &headerLength, 8);
    std::memcpy(pre + 24, &headerCrc, 4);
    out.write(pre, kPreambleBytes);
    out.write(header);
    static const char zeros[kArrayAlignment] = {};
    std::uint64_t written = 0;
    for (std::size_t i = 0; i < table.size(); ++i) {
        out.write(zeros, table[i].offset - out.size());
        const char* p = static_cast<const char*>(sources[i].data);
        for (std::uint64_t done = 0; done < sources[i].bytes;) {
            const std::uint64_t n = std::min(kChunkBytes, sources[i].bytes - done);
            out.write(p + done, n);
            done += n, written += n;
            if (progress && total) progress(double(written) / double(total));
        }
    }
    out.write(zeros, alignUp(out.size()) - out.size());
    out.commit();
    if (progress) progress(1.0);
    return out.size();
}

CacheHeader readPreparedCacheHeader(const std::string& path) {
    InputFile in(path, true);
    return parseHeader(in).header;
}

PreparedMesh readPreparedCache(const std::string& path, const CacheKey& expected,
                               LoadBudget& budget, CacheHeader* header,
                               const std::function<void(double)>& progress) {
    InputFile in(path, true);
    ParsedHeader parsed = parseHeader(in);
    if (header) *header = parsed.header;
    const std::string why = cacheKeyMismatch(parsed.header.key, expected);
    if (!why.empty()) throw StaleCacheError(path, why);

    PreparedMesh m = std::move(parsed.mesh);
    std::size_t next = 0;
    std::uint64_t done = 0;
    const std::uint64_t total = std::max<std::uint64_t>(1, parsed.header.arrayBytes);
    forEachArray(m, [&](const char* name, auto& v) {
        using T = typename std::decay_t<decltype(v)>::value_type;
        if (next >= parsed.table.size())
            throwError(ErrorKind::Parse, path,
                       "the prepared cache's array table ends before '" + std::string(name) +
                           "' (a damaged or foreign file)");
        const ArrayEntry& e = parsed.table[next++];
        if (e.name != name)
            throwError(ErrorKind::Parse, path,
                       "array " + std::to_string(next - 1) + " of the prepared cache is '" +
                           e.name + "', expected '" + name + "'");
        if (e.elementSize != sizeof(T))
            throwError(ErrorKind::Parse, path,
                       "array '" + e.name + "' has " + std::to_string(e.elementSize) +
                           "-byte elements, this uvr's are " + std::to_string(sizeof(T)) +
                           " bytes (prepared by another build?)");
        if (e.offset > in.size || e.count > (in.size - e.offset) / sizeof(T))
            throwError(ErrorKind::Parse, path,
                       "array '" + e.name + "' of " + std::to_string(e.count) + " elements at " +
                           atByte(e.offset) + " reaches beyond the file's " +
                           std::to_string(in.size) + " bytes (truncated?)");
        // Every index into an array is 32-bit (cell ids, block bases, node and grid indices).
        if (e.count > 0xffffffffull)
            throwError(ErrorKind::Parse, path,
                       "array '" + e.name + "' of " + std::to_string(e.count) +
                           " elements: more than 32-bit indices reach (a damaged or crafted file)");
        budget.charge(path, "array '" + e.name + "'", e.count, sizeof(T));
        v.resize(e.count);
        const std::uint64_t bytes = e.count * sizeof(T);
        in.read(e.offset, v.data(), bytes, name, [&](std::uint64_t n) {
            done += n;
            if (progress) progress(double(done) / double(total));
        });
        if (parallelCrc(v.data(), bytes) != e.crc)
            throwError(ErrorKind::Parse, path,
                       "array '" + e.name + "' (" + mib(bytes) + " at " + atByte(e.offset) +
                           ") fails its CRC32 check: the file is damaged");
    });
    if (next != parsed.table.size())
        throwError(ErrorKind::Parse, path,
                   "the prepared cache lists " + std::to_string(parsed.table.size()) +
                       " arrays, expected " + std::to_string(next));
    checkConsistent(m, parsed.tetCount, path);
    checkIndices(m, parsed.tetCount, path);
    m.cacheFile = path;
    return m;
}

}  // namespace uvr
