// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtk_legacy.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/io/scalar_type.h"
#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/mesh/io/vtk_number.h"

namespace uvr {

namespace {

/// Most components an attribute or FIELD array may declare.
constexpr std::int64_t kMaxComponents = 1 << 20;

bool isBlank(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

bool isSpace(char c) {
    return c == '\n' || isBlank(c);
}

char toLowerAscii(char c) {
    return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
}

bool equalsNoCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
        if (toLowerAscii(a[i]) != toLowerAscii(b[i])) return false;
    return true;
}

std::string lowerCase(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = toLowerAscii(c);
    return out;
}

std::string upperCase(std::string_view s) {
    std::string out(s);
    for (char& c : out)
        if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
    return out;
}

/// Quotes text for a one-line error message: at most 40 characters, other bytes as \xNN.
std::string quote(std::string_view s) {
    static const char* kHex = "0123456789abcdef";
    std::string out = "'";
    const std::size_t n = std::min<std::size_t>(s.size(), 40);
    for (std::size_t i = 0; i < n; ++i) {
        const auto c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += static_cast<char>(c);
        } else {
            out += "\\x";
            out += kHex[c >> 4];
            out += kHex[c & 15];
        }
    }
    if (s.size() > n) out += "...";
    return out + "'";
}

int hexDigit(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    c = toLowerAscii(c);
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return -1;
}

/// Decodes VTK's percent-encoding of array names ("my%20field" -> "my field"); a '%' not
/// followed by two hex digits is kept as written (files older than the encoding).
std::string decodeName(std::string_view s) {
    std::string out;
    for (std::size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '%' && i + 2 < s.size() && hexDigit(s[i + 1]) >= 0 && hexDigit(s[i + 2]) >= 0) {
            out += static_cast<char>(hexDigit(s[i + 1]) * 16 + hexDigit(s[i + 2]));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

/// A keyword line: its whitespace-separated tokens and where it starts.
struct KeywordLine {
    std::vector<std::string_view> tokens;
    std::uint64_t line = 0;
    std::uint64_t offset = 0;

    /// The whole line re-joined with single spaces, for messages.
    std::string text() const {
        std::string s;
        for (std::string_view t : tokens) {
            if (!s.empty()) s += ' ';
            s.append(t);
        }
        return s;
    }
};

/// An array about to be read, described for error messages ("expected 2288 point triples").
struct ArrayDesc {
    std::uint64_t tuples = 0;
    std::int64_t components = 1;
    std::string unit;  ///< plural noun for the tuples, e.g. "point triples"
};

/// Keyword-driven reader of one legacy VTK file held in memory. Positions are tracked as a
/// byte offset and, for ASCII files, a line number, so every error can say where it happened.
class LegacyParser {
public:
    LegacyParser(const std::string& file, const std::vector<char>& bytes,
                 const ReadOptions& options)
        : file_(file), data_(bytes.data()), size_(bytes.size()), options_(options) {}

    Mesh parse();

private:
    /// Sequential reader of one array's numbers (ASCII tokens or big-endian binary elements);
    /// its constructor refuses counts the rest of the file cannot hold.
    class Values {
    public:
        Values(LegacyParser& p, ArrayDesc desc, ScalarType type, const KeywordLine& kw);
        /// Total number of values (tuples * components).
        std::uint64_t total() const { return total_; }
        /// Next value as a double.
        double nextDouble();
        /// Next value as an exact integer.
        std::int64_t nextInt();
        /// Location of the value read last ("line N" or "byte N").
        std::string where() const;

    private:
        std::string_view token();
        LegacyParser& p_;
        ArrayDesc desc_;
        ScalarType type_;
        std::uint64_t total_ = 0;
        std::uint64_t index_ = 0;
        const unsigned char* bin_ = nullptr;
        std::uint64_t binOffset_ = 0;
        std::uint64_t lastLine_ = 0;  // line of the last ASCII token, or of the keyword
    };

    // Cursor.
    void skipSpace();
    KeywordLine readKeywordLine();
    std::string_view readRawLine();
    bool nextTokenIs(std::string_view word);

    // Locations and errors.
    std::string where(std::uint64_t line, std::uint64_t offset) const {
        return binary_ ? atByte(offset) : atLine(line);
    }
    std::string where(const KeywordLine& kw) const { return where(kw.line, kw.offset); }
    std::string here() const { return where(line_, pos_); }
    [[noreturn]] void fail(const std::string& at, const std::string& message) const {
        throwParseError(file_, at, message);
    }
    [[noreturn]] void failKind(ErrorKind kind, const std::string& at,
                               const std::string& message) const {
        throwError(kind, file_, at + ": " + message);
    }

    // Tokens of keyword lines.
    void requireTokens(const KeywordLine& kw, std::size_t n, const char* usage) const;
    std::uint64_t parseCount(const KeywordLine& kw, std::size_t i, const char* what) const;
    ScalarType parseType(const KeywordLine& kw, std::size_t i) const;
    std::int64_t parseComponents(const KeywordLine& kw, std::size_t i, std::int64_t maxCount) const;

    // Arrays.
    std::vector<float> readFloats(const ArrayDesc& desc, ScalarType type, const KeywordLine& kw);
    void skipMetadata();

    // Sections.
    void readHeader();
    void readPoints(const KeywordLine& kw);
    void readCells(const KeywordLine& kw);
    void readClassicCells(const KeywordLine& kw, std::uint64_t cellCount, std::uint64_t size);
    void readOffsetCells(std::uint64_t offsetCount, std::uint64_t connectivitySize);
    void readCellTypes(const KeywordLine& kw);
    void readAttributes(KeywordLine kw);
    void readFieldData(const KeywordLine& kw, const Association* association, std::uint64_t tuples);
    void addField(std::string_view name, Association association, std::int64_t components,
                  std::vector<float> values);

    const std::string& file_;
    const char* data_;
    std::uint64_t size_;
    const ReadOptions& options_;
    std::uint64_t pos_ = 0;
    std::uint64_t line_ = 1;
    bool binary_ = false;
    bool swap_ = hostIsLittleEndian();  // binary legacy files are big-endian
    std::int64_t lastComponents_ = 1;   // of the array read last, for METADATA COMPONENT_NAMES
    Mesh mesh_;
    VtkCellArrays cells_;
    std::uint64_t cellCount_ = 0;
    bool havePoints_ = false;
    bool haveCells_ = false;
    bool haveTypes_ = false;
};

// ---------------------------------------------------------------------------------------------
// Cursor

void LegacyParser::skipSpace() {
    while (pos_ < size_) {
        const char c = data_[pos_];
        if (c == '\n') {
            ++line_;
        } else if (!isBlank(c)) {
            break;
        }
        ++pos_;
    }
}

KeywordLine LegacyParser::readKeywordLine() {
    skipSpace();
    KeywordLine kw;
    kw.line = line_;
    kw.offset = pos_;
    while (pos_ < size_ && data_[pos_] != '\n') {
        if (isBlank(data_[pos_])) {
            ++pos_;
            continue;
        }
        const std::uint64_t start = pos_;
        while (pos_ < size_ && !isSpace(data_[pos_])) ++pos_;
        kw.tokens.emplace_back(data_ + start, pos_ - start);
    }
    if (pos_ < size_) {  // binary data starts right after this newline
        ++pos_;
        ++line_;
    }
    return kw;
}

std::string_view LegacyParser::readRawLine() {
    const std::uint64_t start = pos_;
    while (pos_ < size_ && data_[pos_] != '\n') ++pos_;
    std::string_view s(data_ + start, pos_ - start);
    if (pos_ < size_) {
        ++pos_;
        ++line_;
    }
    return s;
}

bool LegacyParser::nextTokenIs(std::string_view word) {
    const std::uint64_t savedPos = pos_, savedLine = line_;
    skipSpace();
    const std::uint64_t start = pos_;
    while (pos_ < size_ && !isSpace(data_[pos_])) ++pos_;
    const bool match = equalsNoCase(std::string_view(data_ + start, pos_ - start), word);
    pos_ = savedPos;
    line_ = savedLine;
    return match;
}

// ---------------------------------------------------------------------------------------------
// Keyword-line tokens

void LegacyParser::requireTokens(const KeywordLine& kw, std::size_t n, const char* usage) const {
    if (kw.tokens.size() < n)
        fail(where(kw), std::string("expected '") + usage + "', got " + quote(kw.text()));
}

std::uint64_t LegacyParser::parseCount(const KeywordLine& kw, std::size_t i,
                                       const char* what) const {
    const std::string_view t = kw.tokens[i];
    const std::optional<std::int64_t> parsed = parseVtkInteger(t);
    if (!parsed)
        fail(where(kw),
             std::string("expected ") + what + " in " + quote(kw.text()) + ", got " + quote(t));
    const std::int64_t v = *parsed;
    if (v < 0)
        fail(where(kw),
             std::string("negative ") + what + " " + std::to_string(v) + " in " + quote(kw.text()));
    return static_cast<std::uint64_t>(v);
}

ScalarType LegacyParser::parseType(const KeywordLine& kw, std::size_t i) const {
    const std::string name = lowerCase(kw.tokens[i]);
    if (name == "bit" || name == "string" || name == "utf8_string" || name == "variant" ||
        name == "unicode_string")
        failKind(ErrorKind::Unsupported, where(kw),
                 "data type '" + name + "' is not supported (numeric arrays only)");
    const auto type = parseLegacyTypeName(name == "vtkidtype" ? "vtkIdType" : name);
    if (!type) fail(where(kw), "unknown data type " + quote(kw.tokens[i]));
    return *type;
}

std::int64_t LegacyParser::parseComponents(const KeywordLine& kw, std::size_t i,
                                           std::int64_t maxCount) const {
    const std::uint64_t n = parseCount(kw, i, "a component count");
    if (n < 1 || n > static_cast<std::uint64_t>(maxCount))
        fail(where(kw), "component count " + std::to_string(n) + " outside [1, " +
                            std::to_string(maxCount) + "] in " + quote(kw.text()));
    return static_cast<std::int64_t>(n);
}

// ---------------------------------------------------------------------------------------------
// Arrays

LegacyParser::Values::Values(LegacyParser& p, ArrayDesc desc, ScalarType type,
                             const KeywordLine& kw)
    : p_(p), desc_(std::move(desc)), type_(type), lastLine_(kw.line) {
    const auto comps = static_cast<std::uint64_t>(desc_.components);
    const std::uint64_t esize = scalarSize(type);
    const std::uint64_t remaining = p.size_ - p.pos_;
    const std::uint64_t limit = std::numeric_limits<std::uint64_t>::max() / 16;
    if (desc_.tuples > limit / comps)
        p.failKind(ErrorKind::Resource, p.where(kw),
                   quote(kw.text()) + " declares more values than any file can hold");
    total_ = desc_.tuples * comps;
    if (p.binary_) {
        // Binary: exactly total * size bytes must follow. Data larger than the whole file is an
        // absurd count (Resource); data larger than the rest of it, a cut-short file (Parse).
        const std::uint64_t bytes = total_ * esize;
        if (bytes > remaining) {
            const std::string msg =
                quote(kw.text()) + ": expected " + std::to_string(desc_.tuples) + " " + desc_.unit +
                ", file ends after " + std::to_string(remaining / (comps * esize)) + " (" +
                std::to_string(bytes) + " bytes needed, " + std::to_string(remaining) + " left)";
            if (bytes > p.size_)
                p.failKind(ErrorKind::Resource, atByte(p.pos_),
                           msg + "; more than the whole file holds");
            p.fail(atByte(p.pos_), msg);
        }
        bin_ = reinterpret_cast<const unsigned char*>(p.data_ + p.pos_);
        binOffset_ = p.pos_;
        p.pos_ += bytes;
        return;
    }
    // ASCII: N numbers take at least 2N - 1 bytes (digits and separators).
    const std::uint64_t minBytes = total_ == 0 ? 0 : 2 * total_ - 1;
    if (minBytes > p.size_)
        p.failKind(ErrorKind::Resource, p.where(kw),
                   quote(kw.text()) + " needs at least " + std::to_string(minBytes) +
                       " bytes of ASCII data, more than the whole file (" +
                       std::to_string(p.size_) + " bytes)");
    if (minBytes > remaining) {
        // Truncated: scan without storing; this reports the exact end or bad token.
        for (std::uint64_t i = 0; i < total_; ++i) nextDouble();
        p.fail(p.where(kw), "expected " + std::to_string(desc_.tuples) + " " + desc_.unit);
    }
}

std::string_view LegacyParser::Values::token() {
    p_.skipSpace();
    if (p_.pos_ >= p_.size_)
        p_.fail(atLine(lastLine_),
                "expected " + std::to_string(desc_.tuples) + " " + desc_.unit +
                    ", file ends after " +
                    std::to_string(index_ / static_cast<std::uint64_t>(desc_.components)));
    lastLine_ = p_.line_;
    const std::uint64_t start = p_.pos_;
    while (p_.pos_ < p_.size_ && !isSpace(p_.data_[p_.pos_])) ++p_.pos_;
    return {p_.data_ + start, p_.pos_ - start};
}

double LegacyParser::Values::nextDouble() {
    if (bin_) return loadAsDouble(bin_, type_, index_++, p_.swap_);
    const std::string_view t = token();
    const std::optional<double> v = parseVtkReal(t);
    if (!v)
        p_.fail(atLine(lastLine_), "expected a number (value " + std::to_string(index_ + 1) +
                                       " of " + std::to_string(total_) + " in " + desc_.unit +
                                       "), got " + quote(t));
    ++index_;
    return *v;
}

std::int64_t LegacyParser::Values::nextInt() {
    if (bin_) return loadAsInt64(bin_, type_, index_++, p_.swap_);
    const std::string_view t = token();
    const std::optional<std::int64_t> v = parseVtkInteger(t);
    if (!v)
        p_.fail(atLine(lastLine_), "expected an integer (value " + std::to_string(index_ + 1) +
                                       " of " + std::to_string(total_) + " in " + desc_.unit +
                                       "), got " + quote(t));
    ++index_;
    return *v;
}

std::string LegacyParser::Values::where() const {
    if (bin_) {
        const std::uint64_t i = index_ == 0 ? 0 : index_ - 1;
        return atByte(binOffset_ + i * scalarSize(type_));
    }
    return atLine(lastLine_);
}

std::vector<float> LegacyParser::readFloats(const ArrayDesc& desc, ScalarType type,
                                            const KeywordLine& kw) {
    Values values(*this, desc, type, kw);
    checkAllocation(file_, desc.unit, values.total(), sizeof(float), options_.maxMemoryBytes);
    options_.budget->charge(file_, desc.unit, values.total(), sizeof(float));
    std::vector<float> out(values.total());
    for (float& v : out) v = static_cast<float>(values.nextDouble());
    lastComponents_ = desc.components;
    return out;
}

void LegacyParser::skipMetadata() {
    // VTK >= 8 array metadata: COMPONENT_NAMES (one line per component, possibly empty) and
    // INFORMATION entries, ended by an empty line (IOLegacyInformationFormat).
    while (pos_ < size_) {
        const std::string_view line = readRawLine();
        std::size_t i = 0;
        while (i < line.size() && isBlank(line[i])) ++i;
        if (i == line.size()) return;
        std::size_t j = i;
        while (j < line.size() && !isBlank(line[j])) ++j;
        if (equalsNoCase(line.substr(i, j - i), "COMPONENT_NAMES"))
            for (std::int64_t c = 0; c < lastComponents_ && pos_ < size_; ++c) readRawLine();
    }
}

// ---------------------------------------------------------------------------------------------
// Sections

void LegacyParser::readHeader() {
    if (size_ == 0) fail(atLine(1), "expected '# vtk DataFile Version X.Y', the file is empty");
    std::string_view first = readRawLine();
    while (!first.empty() && isBlank(first.back())) first.remove_suffix(1);
    constexpr std::string_view kMagic = "# vtk DataFile Version";
    if (first.size() < kMagic.size() || !equalsNoCase(first.substr(0, kMagic.size()), kMagic))
        fail(atLine(1), "expected '# vtk DataFile Version X.Y', got " + quote(first));
    std::string_view version = first.substr(kMagic.size());
    while (!version.empty() && isBlank(version.front())) version.remove_prefix(1);
    int major = -1, minor = -1;
    const char* e = version.data() + version.size();
    auto r = std::from_chars(version.data(), e, major);
    if (r.ec == std::errc() && r.ptr != e && *r.ptr == '.')
        r = std::from_chars(r.ptr + 1, e, minor);
    if (r.ec != std::errc() || r.ptr != e || major < 0 || minor < 0)
        fail(atLine(1), "expected a file version X.Y, got " + quote(version));
    if (major < 1 || major > 5 || (major == 5 && minor > 1))
        failKind(ErrorKind::Unsupported, atLine(1),
                 "file version " + std::string(version) + " is not supported (1.0 to 5.1)");

    if (pos_ >= size_) fail(atLine(2), "expected a title line, the file ends");
    readRawLine();  // title

    const KeywordLine format = readKeywordLine();
    if (format.tokens.empty()) fail(where(format), "expected ASCII or BINARY, the file ends");
    if (equalsNoCase(format.tokens[0], "BINARY")) {
        binary_ = true;
    } else if (!equalsNoCase(format.tokens[0], "ASCII")) {
        fail(where(format), "expected ASCII or BINARY, got " + quote(format.tokens[0]));
    }

    const KeywordLine dataset = readKeywordLine();
    if (dataset.tokens.empty()) fail(where(dataset), "expected keyword DATASET, the file ends");
    if (!equalsNoCase(dataset.tokens[0], "DATASET"))
        fail(where(dataset), "expected keyword DATASET, got " + quote(dataset.tokens[0]));
    requireTokens(dataset, 2, "DATASET type");
    if (!equalsNoCase(dataset.tokens[1], "UNSTRUCTURED_GRID"))
        failKind(ErrorKind::Unsupported, where(dataset),
                 "DATASET " + upperCase(dataset.tokens[1]).substr(0, 40) +
                     " is not supported (only UNSTRUCTURED_GRID)");
}

void LegacyParser::readPoints(const KeywordLine& kw) {
    requireTokens(kw, 3, "POINTS count type");
    if (havePoints_) fail(where(kw), "a second POINTS section");
    const std::uint64_t n = parseCount(kw, 1, "a point count");
    const ScalarType type = parseType(kw, 2);
    if (n > std::numeric_limits<std::uint32_t>::max() && 3 * n <= size_)
        failKind(ErrorKind::Unsupported, where(kw),
                 "POINTS " + std::to_string(n) + ": more than 2^32 - 1 points");
    const std::vector<float> xyz = readFloats({n, 3, "point triples"}, type, kw);
    checkAllocation(file_, "POINTS", n, sizeof(Vec3f), options_.maxMemoryBytes);
    options_.budget->charge(file_, "POINTS", n, sizeof(Vec3f));
    mesh_.points.resize(n);
    for (std::uint64_t i = 0; i < n; ++i)
        mesh_.points[i] = Vec3f(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    options_.budget->release(xyz.size() * sizeof(float));
    havePoints_ = true;
}

void LegacyParser::readCells(const KeywordLine& kw) {
    requireTokens(kw, 3, "CELLS count size");
    if (haveCells_) fail(where(kw), "a second CELLS section");
    const std::uint64_t first = parseCount(kw, 1, "a cell count");
    const std::uint64_t second = parseCount(kw, 2, "a CELLS size");
    if (nextTokenIs("OFFSETS")) {
        readOffsetCells(first, second);  // file version 5.x: CELLS nOffsets nConnectivity
    } else {
        readClassicCells(kw, first, second);
    }
    haveCells_ = true;
}

void LegacyParser::readClassicCells(const KeywordLine& kw, std::uint64_t cellCount,
                                    std::uint64_t size) {
    // Records "k id_1 ... id_k", int32 in binary; size counts all integers.
    if (cellCount > size)
        fail(where(kw), quote(kw.text()) + ": " + std::to_string(cellCount) +
                            " cells need at least " + std::to_string(cellCount) + " integers");
    Values values(*this, {size, 1, "CELLS integers"}, ScalarType::Int32, kw);
    checkAllocation(file_, "CELLS offsets", cellCount + 1, sizeof(std::int64_t),
                    options_.maxMemoryBytes);
    checkAllocation(file_, "CELLS connectivity", size - cellCount, sizeof(std::int64_t),
                    options_.maxMemoryBytes);
    options_.budget->charge(file_, "CELLS offsets", cellCount + 1, sizeof(std::int64_t));
    options_.budget->charge(file_, "CELLS connectivity", size - cellCount, sizeof(std::int64_t));
    cells_.offsets.reserve(cellCount + 1);
    cells_.offsets.push_back(0);
    cells_.connectivity.reserve(size - cellCount);
    std::uint64_t remaining = size;
    for (std::uint64_t c = 0; c < cellCount; ++c) {
        if (remaining == 0)
            fail(values.where(), "cell " + std::to_string(c) +
                                     " starts past the end of CELLS size " + std::to_string(size));
        const std::int64_t k = values.nextInt();
        --remaining;
        if (k < 0 || static_cast<std::uint64_t>(k) > remaining)
            fail(values.where(), "cell " + std::to_string(c) + " lists " + std::to_string(k) +
                                     " points, but only " + std::to_string(remaining) +
                                     " integers remain of CELLS size " + std::to_string(size));
        for (std::int64_t j = 0; j < k; ++j) cells_.connectivity.push_back(values.nextInt());
        remaining -= static_cast<std::uint64_t>(k);
        cells_.offsets.push_back(static_cast<std::int64_t>(cells_.connectivity.size()));
    }
    if (remaining != 0)
        fail(where(kw), "CELLS size " + std::to_string(size) + " does not match its " +
                            std::to_string(cellCount) + " records, which hold " +
                            std::to_string(size - remaining) + " integers");
    cellCount_ = cellCount;
    lastComponents_ = 1;
}

void LegacyParser::readOffsetCells(std::uint64_t offsetCount, std::uint64_t connectivitySize) {
    // OFFSETS (cellCount + 1 entries from 0 to connectivitySize), then CONNECTIVITY.
    const KeywordLine offKw = readKeywordLine();
    requireTokens(offKw, 2, "OFFSETS type");
    const ScalarType offType = parseType(offKw, 1);
    if (!isIntegerType(offType))
        fail(where(offKw), "expected an integer type for OFFSETS, got " + quote(offKw.tokens[1]));
    Values offsets(*this, {offsetCount, 1, "OFFSETS entries"}, offType, offKw);
    checkAllocation(file_, "OFFSETS", offsetCount, sizeof(std::int64_t), options_.maxMemoryBytes);
    options_.budget->charge(file_, "OFFSETS", offsetCount, sizeof(std::int64_t));
    cells_.offsets.reserve(offsetCount == 0 ? 1 : offsetCount);
    std::int64_t previous = 0;
    for (std::uint64_t i = 0; i < offsetCount; ++i) {
        const std::int64_t o = offsets.nextInt();
        if (i == 0 && o != 0)
            fail(offsets.where(), "OFFSETS must start at 0, got " + std::to_string(o));
        if (o < previous || static_cast<std::uint64_t>(o) > connectivitySize)
            fail(offsets.where(), "OFFSETS entry " + std::to_string(i) + " = " + std::to_string(o) +
                                      " outside [" + std::to_string(previous) + ", " +
                                      std::to_string(connectivitySize) + "]");
        cells_.offsets.push_back(o);
        previous = o;
    }
    if (offsetCount == 0) cells_.offsets.push_back(0);
    lastComponents_ = 1;
    if (nextTokenIs("METADATA")) {
        readKeywordLine();
        skipMetadata();
    }

    const KeywordLine conKw = readKeywordLine();
    if (conKw.tokens.empty() || !equalsNoCase(conKw.tokens[0], "CONNECTIVITY"))
        fail(where(conKw), "expected keyword CONNECTIVITY, got " +
                               (conKw.tokens.empty() ? std::string("the end of the file")
                                                     : quote(conKw.tokens[0])));
    requireTokens(conKw, 2, "CONNECTIVITY type");
    const ScalarType conType = parseType(conKw, 1);
    if (!isIntegerType(conType))
        fail(where(conKw),
             "expected an integer type for CONNECTIVITY, got " + quote(conKw.tokens[1]));
    if (static_cast<std::uint64_t>(previous) != connectivitySize)
        fail(where(conKw), "OFFSETS end at " + std::to_string(previous) +
                               ", expected the CONNECTIVITY size " +
                               std::to_string(connectivitySize));
    Values conn(*this, {connectivitySize, 1, "CONNECTIVITY entries"}, conType, conKw);
    checkAllocation(file_, "CONNECTIVITY", connectivitySize, sizeof(std::int64_t),
                    options_.maxMemoryBytes);
    options_.budget->charge(file_, "CONNECTIVITY", connectivitySize, sizeof(std::int64_t));
    cells_.connectivity.resize(connectivitySize);
    for (std::int64_t& id : cells_.connectivity) id = conn.nextInt();
    cellCount_ = offsetCount == 0 ? 0 : offsetCount - 1;
}

void LegacyParser::readCellTypes(const KeywordLine& kw) {
    requireTokens(kw, 2, "CELL_TYPES count");
    if (!haveCells_) fail(where(kw), "CELL_TYPES without a preceding CELLS section");
    if (haveTypes_) fail(where(kw), "a second CELL_TYPES section");
    const std::uint64_t n = parseCount(kw, 1, "a cell count");
    if (n != cellCount_)
        fail(where(kw), "CELL_TYPES " + std::to_string(n) + " does not match the " +
                            std::to_string(cellCount_) + " cells of CELLS");
    Values values(*this, {n, 1, "cell types"}, ScalarType::Int32, kw);
    checkAllocation(file_, "CELL_TYPES", n, sizeof(std::int32_t), options_.maxMemoryBytes);
    options_.budget->charge(file_, "CELL_TYPES", n, sizeof(std::int32_t));
    cells_.types.resize(n);
    for (std::uint64_t c = 0; c < n; ++c) {
        const std::int64_t t = values.nextInt();
        if (t < std::numeric_limits<std::int32_t>::min() ||
            t > std::numeric_limits<std::int32_t>::max())
            fail(values.where(), "cell " + std::to_string(c) + ": cell type " + std::to_string(t) +
                                     " out of range");
        cells_.types[c] = static_cast<std::int32_t>(t);
    }
    haveTypes_ = true;
    lastComponents_ = 1;
}

void LegacyParser::addField(std::string_view name, Association association, std::int64_t components,
                            std::vector<float> values) {
    Field f;
    f.name = decodeName(name);
    f.association = association;
    f.components = static_cast<int>(components);
    f.values = std::move(values);
    mesh_.fields.push_back(std::move(f));
}

void LegacyParser::readFieldData(const KeywordLine& kw, const Association* association,
                                 std::uint64_t tuples) {
    // FIELD name numArrays, then per array "name numComponents numTuples type" and its data.
    requireTokens(kw, 3, "FIELD name arrayCount");
    const std::uint64_t arrays = parseCount(kw, 2, "an array count");
    for (std::uint64_t a = 0; a < arrays;) {
        const KeywordLine head = readKeywordLine();
        if (head.tokens.empty())
            fail(where(head), "expected " + std::to_string(arrays) +
                                  " FIELD arrays, file ends after " + std::to_string(a));
        if (equalsNoCase(head.tokens[0], "METADATA")) {
            skipMetadata();
            continue;
        }
        ++a;
        if (equalsNoCase(head.tokens[0], "NULL_ARRAY")) continue;
        requireTokens(head, 4, "arrayName numComponents numTuples type");
        const std::int64_t comps = parseComponents(head, 1, kMaxComponents);
        const std::uint64_t n = parseCount(head, 2, "a tuple count");
        const ScalarType type = parseType(head, 3);
        if (association && n != tuples)
            fail(where(head),
                 "FIELD array " + quote(decodeName(head.tokens[0])) + " has " + std::to_string(n) +
                     " tuples, expected " + std::to_string(tuples) +
                     (*association == Association::Point ? " (POINT_DATA)" : " (CELL_DATA)"));
        std::vector<float> values =
            readFloats({n, comps, "tuples of FIELD array " + quote(head.tokens[0])}, type, head);
        if (association)
            addField(head.tokens[0], *association, comps, std::move(values));
        else
            options_.budget->release(values.size() * sizeof(float));  // dataset FIELD: skipped
    }
}

void LegacyParser::readAttributes(KeywordLine kw) {
    // kw is a POINT_DATA or CELL_DATA line; sections may follow each other in any order.
    for (;;) {
        requireTokens(kw, 2, "POINT_DATA count");
        const bool points = equalsNoCase(kw.tokens[0], "POINT_DATA");
        const Association assoc = points ? Association::Point : Association::Cell;
        const std::uint64_t n = parseCount(kw, 1, "a tuple count");
        const std::uint64_t expected = points ? mesh_.points.size() : cellCount_;
        if (n != expected)
            fail(where(kw), upperCase(kw.tokens[0]) + " " + std::to_string(n) + " does not match " +
                                std::to_string(expected) + (points ? " points" : " cells"));
        for (;;) {
            kw = readKeywordLine();
            if (kw.tokens.empty()) return;
            const std::string key = upperCase(kw.tokens[0]);
            if (key == "POINT_DATA" || key == "CELL_DATA") break;
            if (key == "SCALARS") {
                requireTokens(kw, 3, "SCALARS name type [numComponents]");
                const ScalarType type = parseType(kw, 2);
                const std::int64_t comps =
                    kw.tokens.size() > 3 ? parseComponents(kw, 3, kMaxComponents) : 1;
                if (nextTokenIs("LOOKUP_TABLE")) readKeywordLine();  // optional in older files
                addField(
                    kw.tokens[1], assoc, comps,
                    readFloats({n, comps, "tuples of SCALARS " + quote(kw.tokens[1])}, type, kw));
            } else if (key == "VECTORS" || key == "NORMALS" || key == "TENSORS" ||
                       key == "TENSORS6" || key == "GLOBAL_IDS" || key == "PEDIGREE_IDS") {
                requireTokens(kw, 3, (key + " name type").c_str());
                const ScalarType type = parseType(kw, 2);
                std::int64_t comps = 3;  // VECTORS, NORMALS
                if (key == "TENSORS") comps = 9;
                if (key == "TENSORS6") comps = 6;
                if (key == "GLOBAL_IDS" || key == "PEDIGREE_IDS") comps = 1;
                addField(kw.tokens[1], assoc, comps,
                         readFloats({n, comps, "tuples of " + key + " " + quote(kw.tokens[1])},
                                    type, kw));
            } else if (key == "TEXTURE_COORDINATES") {
                requireTokens(kw, 4, "TEXTURE_COORDINATES name dimension type");
                const std::int64_t comps = parseComponents(kw, 2, 3);
                const ScalarType type = parseType(kw, 3);
                addField(kw.tokens[1], assoc, comps,
                         readFloats({n, comps, "tuples of " + key + " " + quote(kw.tokens[1])},
                                    type, kw));
            } else if (key == "COLOR_SCALARS") {
                // Unsigned bytes in binary, floats in [0, 1] in ASCII; kept as 0..255 like VTK.
                requireTokens(kw, 3, "COLOR_SCALARS name componentCount");
                const std::int64_t comps = parseComponents(kw, 2, kMaxComponents);
                std::vector<float> values =
                    readFloats({n, comps, "tuples of COLOR_SCALARS " + quote(kw.tokens[1])},
                               binary_ ? ScalarType::UInt8 : ScalarType::Float32, kw);
                if (!binary_)
                    for (float& v : values) v = std::round(v * 255.0f);
                addField(kw.tokens[1], assoc, comps, std::move(values));
            } else if (key == "LOOKUP_TABLE") {
                // A colour table for SCALARS: size RGBA entries, skipped.
                requireTokens(kw, 3, "LOOKUP_TABLE name size");
                const std::uint64_t entries = parseCount(kw, 2, "a table size");
                const std::int64_t saved = lastComponents_;
                const std::vector<float> table =
                    readFloats({entries, 4, "lookup table entries"},
                               binary_ ? ScalarType::UInt8 : ScalarType::Float32, kw);
                options_.budget->release(table.size() * sizeof(float));
                lastComponents_ = saved;
            } else if (key == "FIELD") {
                readFieldData(kw, &assoc, n);
            } else if (key == "METADATA") {
                skipMetadata();
            } else {
                fail(where(kw),
                     "expected an attribute keyword (SCALARS, VECTORS, NORMALS, TENSORS, "
                     "TEXTURE_COORDINATES, COLOR_SCALARS, LOOKUP_TABLE, FIELD, POINT_DATA or "
                     "CELL_DATA), got " +
                         quote(kw.tokens[0]));
            }
        }
    }
}

Mesh LegacyParser::parse() {
    readHeader();
    // Geometry: POINTS, CELLS, CELL_TYPES and dataset FIELD data (skipped), in any order, up to
    // the first POINT_DATA or CELL_DATA.
    for (;;) {
        const KeywordLine kw = readKeywordLine();
        const bool needTypes = haveCells_ && !haveTypes_;
        if (kw.tokens.empty()) {
            if (needTypes) fail(where(kw), "expected keyword CELL_TYPES, the file ends");
            break;
        }
        const std::string key = upperCase(kw.tokens[0]);
        if (key == "POINTS") {
            readPoints(kw);
        } else if (key == "CELLS") {
            readCells(kw);
        } else if (key == "CELL_TYPES") {
            readCellTypes(kw);
        } else if (key == "FIELD") {
            readFieldData(kw, nullptr, 0);
        } else if (key == "METADATA") {
            skipMetadata();
        } else if ((key == "POINT_DATA" || key == "CELL_DATA") && !needTypes) {
            readAttributes(kw);
            break;
        } else {
            fail(where(kw), std::string(needTypes ? "expected keyword CELL_TYPES"
                                                  : "expected keyword POINTS, CELLS, CELL_TYPES, "
                                                    "FIELD, POINT_DATA or CELL_DATA") +
                                ", got " + quote(kw.tokens[0]));
        }
    }
    if (!haveCells_) cells_.offsets.assign(1, 0);
    options_.budget->charge(file_, "the cells", cells_.types.size(),
                            sizeof(CellType) + sizeof(std::uint64_t));
    options_.budget->charge(file_, "the cell connectivity", cells_.connectivity.size(),
                            sizeof(std::uint32_t));
    // Cells last: appendVtkCells filters the cell fields read above to the kept cells. A
    // polyhedron's node list is its face stream (what VTK writes in every file version).
    cells_.polyhedronFaces = PolyhedronFaces::Connectivity;
    appendVtkCells(cells_, mesh_, file_, options_.budget);
    return std::move(mesh_);
}

}  // namespace

Mesh readVtkLegacy(const std::string& path, const ReadOptions& options) {
    const BudgetedOptions budgeted(options);
    LoadBudget& budget = budgeted.budget();
    const std::uint64_t heldBefore = budget.used();
    // The size is charged before reading, so a huge (or sparse) file is refused unread.
    const std::vector<char> bytes = readFileCharged(path, budget);
    LegacyParser parser(path, bytes, budgeted.options());
    Mesh mesh = parser.parse();
    budget.resetTo(heldBefore + meshBytes(mesh));  // the file and the raw cells are freed next
    return mesh;
}

}  // namespace uvr
