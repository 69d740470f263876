// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/vtu.h"

#include <expat.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <exception>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string_view>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/mesh/cell_types.h"
#include "uvr/mesh/io/base64.h"
#include "uvr/mesh/io/mesh_merge.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/io/scalar_type.h"
#include "uvr/mesh/io/vtk_cells.h"
#include "uvr/mesh/io/vtk_compression.h"
#include "uvr/mesh/io/vtk_number.h"

namespace uvr {

namespace {

constexpr std::uint64_t kMaxComponents = 1u << 20;

enum class Section { None, Points, Cells, PointData, CellData };
enum class Encoding { Ascii, Binary, Appended };

/// One <DataArray> of a Piece as declared in the XML, with its inline text if any.
struct ArrayDesc {
    std::string name;
    std::optional<ScalarType> type;  // nullopt for String arrays, which are skipped
    std::uint64_t components = 1;
    Encoding encoding = Encoding::Ascii;
    std::uint64_t offset = 0;  // into the appended data
    std::string text;          // inline content (ascii or base64)
    std::uint64_t line = 0;    // line of the start tag
    std::uint64_t textLine = 0;
    std::uint64_t textByte = 0;
    bool haveText = false;
    Section section = Section::None;
    std::string label;               // "Piece 0: DataArray 'offsets'"
    std::uint64_t encodedBytes = 0;  // its share of the file (progress; setEncodedBytes)
};

struct PieceDesc {
    std::uint64_t points = 0;
    std::uint64_t cells = 0;
    std::uint64_t line = 0;
    std::string source;  // .pvtu pieces only
    std::vector<ArrayDesc> arrays;
};

/// What the XML part of a VTK XML file declares.
struct XmlDoc {
    std::string file;
    std::string type;
    bool bigEndian = false;
    std::size_t headerSize = 4;
    VtuCompressor compressor = VtuCompressor::None;
    std::vector<PieceDesc> pieces;
    bool hasAppended = false;
    bool appendedBase64 = false;
    std::uint64_t appendedStart = 0;  // file byte offset just after the '_' marker
    std::uint64_t appendedEnd = 0;    // file byte offset of </AppendedData>
    std::uint64_t fileBytes = 0;      // size of the file
    /// The appended byte ranges read so far: file offset of the start -> end and the array.
    mutable std::map<std::uint64_t, std::pair<std::uint64_t, std::string>> appendedReads;
};

// ---- XML parsing with expat ----

struct ParseState {
    XmlDoc* doc = nullptr;
    XML_Parser parser = nullptr;
    std::vector<std::string> stack;
    Section section = Section::None;
    ArrayDesc* array = nullptr;  // the DataArray being collected (innermost element)
    std::size_t arrayDepth = 0;
    std::exception_ptr error;
};

const char* findAttr(const XML_Char** attrs, const char* name) {
    for (int i = 0; attrs[i]; i += 2)
        if (std::strcmp(attrs[i], name) == 0) return attrs[i + 1];
    return nullptr;
}

std::string trimmed(const char* s) {
    std::string_view v(s);
    while (!v.empty() && std::isspace(static_cast<unsigned char>(v.front()))) v.remove_prefix(1);
    while (!v.empty() && std::isspace(static_cast<unsigned char>(v.back()))) v.remove_suffix(1);
    return std::string(v);
}

[[noreturn]] void failAtLine(ParseState& st, const std::string& message) {
    throwParseError(st.doc->file, atLine(XML_GetCurrentLineNumber(st.parser)), message);
}

std::uint64_t parseCount(ParseState& st, const XML_Char** attrs, const char* attr,
                         const std::string& element, bool required, std::uint64_t fallback) {
    const char* value = findAttr(attrs, attr);
    if (!value) {
        if (!required) return fallback;
        failAtLine(st, element + ": missing attribute " + attr);
    }
    const std::optional<std::uint64_t> v = parseVtkCount(value);
    if (!v)
        failAtLine(st, element + ": expected " + attr + " to be a non-negative integer, got '" +
                           trimmed(value).substr(0, 40) + "'");
    return *v;
}

void onRootElement(ParseState& st, const XML_Char** attrs) {
    XmlDoc& doc = *st.doc;
    const char* type = findAttr(attrs, "type");
    doc.type = type ? type : "";
    if (doc.type != "UnstructuredGrid" && doc.type != "PUnstructuredGrid")
        throwError(ErrorKind::Unsupported, doc.file,
                   "VTKFile type '" + doc.type +
                       "' is not supported: expected UnstructuredGrid or PUnstructuredGrid");
    const char* order = findAttr(attrs, "byte_order");
    const std::string byteOrder = order ? order : "LittleEndian";
    if (byteOrder != "LittleEndian" && byteOrder != "BigEndian")
        failAtLine(
            st, "VTKFile: expected byte_order LittleEndian or BigEndian, got '" + byteOrder + "'");
    doc.bigEndian = byteOrder == "BigEndian";
    const char* header = findAttr(attrs, "header_type");
    const std::string headerType = header ? header : "UInt32";
    if (headerType != "UInt32" && headerType != "UInt64")
        failAtLine(st, "VTKFile: expected header_type UInt32 or UInt64, got '" + headerType + "'");
    doc.headerSize = headerType == "UInt64" ? 8 : 4;
    const char* compressor = findAttr(attrs, "compressor");
    const std::string comp = compressor ? compressor : "";
    if (comp.empty()) return;
    const std::optional<VtuCompressor> known = parseVtuCompressorClass(comp);
    const std::string where = atLine(XML_GetCurrentLineNumber(st.parser));
    if (!known)
        throwError(ErrorKind::Unsupported, doc.file,
                   where + ": compressor '" + comp +
                       "' is not supported: expected vtkZLibDataCompressor, vtkLZ4DataCompressor, "
                       "vtkLZMADataCompressor or none");
    requireVtuCompressor(*known, doc.file + ": " + where);
    doc.compressor = *known;
}

void onDataArray(ParseState& st, const XML_Char** attrs) {
    PieceDesc& piece = st.doc->pieces.back();
    ArrayDesc a;
    a.section = st.section;
    a.line = XML_GetCurrentLineNumber(st.parser);
    const char* name = findAttr(attrs, "Name");
    a.name = name ? name : "";
    if (a.section == Section::Points && a.name.empty()) a.name = "Points";
    a.label = "Piece " + std::to_string(st.doc->pieces.size() - 1) + ": DataArray '" + a.name + "'";
    const char* type = findAttr(attrs, "type");
    if (!type) failAtLine(st, a.label + ": missing attribute type");
    const std::string typeName = type;
    if (typeName != "String") {
        a.type = parseXmlTypeName(typeName);
        if (!a.type)
            failAtLine(st, a.label +
                               ": expected type Int8, UInt8, Int16, UInt16, Int32, UInt32, "
                               "Int64, UInt64, Float32, Float64 or String, got '" +
                               typeName + "'");
    }
    a.components = parseCount(st, attrs, "NumberOfComponents", a.label, false, 1);
    if (a.components == 0 || a.components > kMaxComponents)
        failAtLine(st, a.label + ": expected NumberOfComponents in [1, " +
                           std::to_string(kMaxComponents) + "], got " +
                           std::to_string(a.components));
    const char* format = findAttr(attrs, "format");
    const std::string fmt = format ? format : "";
    if (fmt == "ascii") {
        a.encoding = Encoding::Ascii;
    } else if (fmt == "binary") {
        a.encoding = Encoding::Binary;
    } else if (fmt == "appended") {
        a.encoding = Encoding::Appended;
        a.offset = parseCount(st, attrs, "offset", a.label, true, 0);
    } else {
        failAtLine(st, a.label + ": expected format ascii, binary or appended, got '" + fmt + "'");
    }
    piece.arrays.push_back(std::move(a));
    st.array = &piece.arrays.back();
    st.arrayDepth = st.stack.size();
}

void onStart(ParseState& st, const std::string& name, const XML_Char** attrs) {
    XmlDoc& doc = *st.doc;
    const std::string parent = st.stack.empty() ? "" : st.stack.back();
    st.stack.push_back(name);
    if (st.stack.size() == 1) {
        if (name != "VTKFile") failAtLine(st, "expected the root element VTKFile, got " + name);
        onRootElement(st, attrs);
        return;
    }
    if (name == "Piece" && (parent == "UnstructuredGrid" || parent == "PUnstructuredGrid")) {
        PieceDesc p;
        p.line = XML_GetCurrentLineNumber(st.parser);
        const std::string label = "Piece " + std::to_string(doc.pieces.size());
        if (parent == "UnstructuredGrid") {
            p.points = parseCount(st, attrs, "NumberOfPoints", label, true, 0);
            p.cells = parseCount(st, attrs, "NumberOfCells", label, true, 0);
        } else {
            const char* source = findAttr(attrs, "Source");
            if (!source || !*source) failAtLine(st, label + ": missing attribute Source");
            p.source = source;
        }
        doc.pieces.push_back(std::move(p));
        return;
    }
    if (parent == "Piece" && !doc.pieces.empty()) {
        if (name == "Points") st.section = Section::Points;
        if (name == "Cells") st.section = Section::Cells;
        if (name == "PointData") st.section = Section::PointData;
        if (name == "CellData") st.section = Section::CellData;
        return;
    }
    if (name == "DataArray" && st.section != Section::None && st.stack.size() >= 2 &&
        (parent == "Points" || parent == "Cells" || parent == "PointData" ||
         parent == "CellData")) {
        onDataArray(st, attrs);
        return;
    }
    if (name == "AppendedData" && parent == "VTKFile") {
        const char* encoding = findAttr(attrs, "encoding");
        const std::string enc = encoding ? encoding : "";
        if (enc != "raw" && enc != "base64")
            failAtLine(st, "AppendedData: expected encoding raw or base64, got '" + enc + "'");
        doc.hasAppended = true;
        doc.appendedBase64 = enc == "base64";
    }
}

void XMLCALL startHandler(void* data, const XML_Char* name, const XML_Char** attrs) {
    auto& st = *static_cast<ParseState*>(data);
    if (st.error) return;
    try {
        onStart(st, name, attrs);
    } catch (...) {
        st.error = std::current_exception();
        XML_StopParser(st.parser, XML_FALSE);
    }
}

void XMLCALL endHandler(void* data, const XML_Char* name) {
    auto& st = *static_cast<ParseState*>(data);
    if (st.error || st.stack.empty()) return;
    if (st.array && st.stack.size() == st.arrayDepth) st.array = nullptr;
    const std::string n = name;
    if (n == "Points" || n == "Cells" || n == "PointData" || n == "CellData" || n == "Piece")
        st.section = Section::None;
    st.stack.pop_back();
}

void XMLCALL textHandler(void* data, const XML_Char* s, int len) {
    auto& st = *static_cast<ParseState*>(data);
    if (st.error || !st.array || st.stack.size() != st.arrayDepth) return;
    try {
        if (!st.array->haveText) {
            st.array->haveText = true;
            st.array->textLine = XML_GetCurrentLineNumber(st.parser);
            st.array->textByte = static_cast<std::uint64_t>(XML_GetCurrentByteIndex(st.parser));
        }
        st.array->text.append(s, static_cast<std::size_t>(len));
    } catch (...) {
        st.error = std::current_exception();
        XML_StopParser(st.parser, XML_FALSE);
    }
}

/// Parses the XML of a VTK XML file; raw appended data (not XML) is located but not parsed.
XmlDoc parseXml(const std::string& path, const std::vector<char>& bytes) {
    XmlDoc doc;
    doc.file = path;
    doc.fileBytes = bytes.size();
    std::string_view all(bytes.data(), bytes.size());
    // Step 1: the XML ends at the <AppendedData ...> start tag when there is one.
    std::size_t xmlEnd = all.size();
    std::size_t appendedTag = all.find("<AppendedData");
    std::size_t dataStart = 0;
    bool selfClosing = false;
    if (appendedTag != std::string_view::npos) {
        const std::size_t close = all.find('>', appendedTag);
        if (close == std::string_view::npos)
            throwParseError(path, atByte(appendedTag),
                            "the <AppendedData> start tag is not closed (file truncated?)");
        xmlEnd = close + 1;
        selfClosing = all[close - 1] == '/';
        dataStart = xmlEnd;
    }

    // Step 2: expat over the XML part, then synthetic end tags for the elements left open.
    XML_Parser parser = XML_ParserCreate(nullptr);
    if (!parser) throwError(ErrorKind::Resource, path, "cannot create an XML parser");
    ParseState st;
    st.doc = &doc;
    st.parser = parser;
    XML_SetUserData(parser, &st);
    XML_SetElementHandler(parser, startHandler, endHandler);
    XML_SetCharacterDataHandler(parser, textHandler);
    auto fail = [&](XML_Status status) {
        if (st.error) {
            XML_ParserFree(parser);
            std::rethrow_exception(st.error);
        }
        if (status == XML_STATUS_ERROR) {
            const std::string where = atLine(XML_GetCurrentLineNumber(parser));
            const std::string message = "XML syntax error at column " +
                                        std::to_string(XML_GetCurrentColumnNumber(parser) + 1) +
                                        ": " + XML_ErrorString(XML_GetErrorCode(parser));
            XML_ParserFree(parser);
            throwParseError(path, where, message);
        }
    };
    constexpr std::size_t kChunk = std::size_t(1) << 26;
    const bool finalInOne = appendedTag == std::string_view::npos;
    for (std::size_t pos = 0; pos < xmlEnd || pos == 0;) {
        const std::size_t n = std::min(kChunk, xmlEnd - pos);
        const bool last = pos + n >= xmlEnd;
        fail(XML_Parse(parser, bytes.data() + pos, static_cast<int>(n),
                       (last && finalInOne) ? XML_TRUE : XML_FALSE));
        pos += n;
        if (n == 0) break;
    }
    if (!finalInOne) {
        std::string closing;
        for (auto it = st.stack.rbegin(); it != st.stack.rend(); ++it) closing += "</" + *it + ">";
        fail(XML_Parse(parser, closing.data(), static_cast<int>(closing.size()), XML_TRUE));
    }
    XML_ParserFree(parser);

    // Step 3: the appended data runs from after '_' to </AppendedData>.
    if (doc.hasAppended && !selfClosing) {
        std::size_t p = dataStart;
        while (p < all.size() && std::isspace(static_cast<unsigned char>(all[p]))) ++p;
        if (p >= all.size() || all[p] != '_')
            throwParseError(path, atByte(p),
                            "AppendedData: expected '_' before the appended data, got " +
                                (p >= all.size() ? std::string("the end of the file")
                                                 : "'" + std::string(1, all[p]) + "'"));
        doc.appendedStart = p + 1;
        const std::size_t end = all.rfind("</AppendedData>");
        if (end == std::string_view::npos || end < doc.appendedStart)
            throwParseError(path, atByte(all.size()),
                            "expected </AppendedData> after the appended data (file truncated?)");
        doc.appendedEnd = end;
    }
    // Each array's share of the file (progress): its inline text, or the appended bytes up to
    // the next array's offset.
    std::vector<std::uint64_t> offsets;
    for (const PieceDesc& piece : doc.pieces)
        for (const ArrayDesc& a : piece.arrays)
            if (a.encoding == Encoding::Appended) offsets.push_back(a.offset);
    std::sort(offsets.begin(), offsets.end());
    const std::uint64_t appended = doc.appendedEnd - doc.appendedStart;
    for (PieceDesc& piece : doc.pieces)
        for (ArrayDesc& a : piece.arrays) {
            if (a.encoding != Encoding::Appended) {
                a.encodedBytes = a.text.size();
                continue;
            }
            const auto next = std::upper_bound(offsets.begin(), offsets.end(), a.offset);
            const std::uint64_t end = next == offsets.end() ? appended : *next;
            a.encodedBytes = end > a.offset ? end - a.offset : 0;
        }
    return doc;
}

// ---- binary payloads ----

/// Sequential bytes of one array's binary payload: raw appended bytes or base64 text.
class ByteSource {
public:
    ByteSource(const char* raw, std::size_t size, std::uint64_t fileOffset)
        : raw_(raw), size_(size), fileBase_(fileOffset) {}
    ByteSource(std::string_view text, Base64Origin origin) : b64_(Base64Reader(text, origin)) {}

    void read(std::size_t n, std::vector<unsigned char>& out) {
        if (b64_) return b64_->read(n, out);
        out.insert(out.end(), raw_ + pos_, raw_ + pos_ + n);  // n checked against remaining()
        pos_ += n;
    }
    /// Reads n bytes (checked against remaining()) to dst.
    void readInto(std::size_t n, unsigned char* dst) {
        if (!b64_) {
            std::memcpy(dst, raw_ + pos_, n);
            pos_ += n;
            return;
        }
        std::vector<unsigned char> chunk;
        for (std::size_t done = 0; done < n;) {
            const std::size_t k = std::min<std::size_t>(n - done, std::size_t(1) << 16);
            chunk.clear();
            b64_->read(k, chunk);
            std::memcpy(dst + done, chunk.data(), k);
            done += k;
        }
    }
    /// True for raw bytes, whose file offsets advance one per byte (base64 text: four per three).
    bool raw() const { return !b64_; }
    std::uint64_t remaining() const { return b64_ ? b64_->remainingBound() : size_ - pos_; }
    std::uint64_t fileOffset() const { return b64_ ? b64_->fileOffset() : fileBase_ + pos_; }

private:
    std::optional<Base64Reader> b64_;
    const char* raw_ = nullptr;
    std::size_t size_ = 0, pos_ = 0;
    std::uint64_t fileBase_ = 0;
};

std::uint64_t loadHeaderInt(const unsigned char* p, std::size_t size, bool bigEndian) {
    std::uint64_t v = 0;
    for (std::size_t k = 0; k < size; ++k) {
        const std::size_t byte = bigEndian ? k : size - 1 - k;
        v = (v << 8) | p[byte];
    }
    return v;
}

/// An allocator that default-initialises: a buffer sized for what a header declares is not
/// zero-filled (pages never written are never touched), so only what decompression really
/// produces occupies memory.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
    using value_type = T;
    template <class U>
    struct rebind {
        using other = DefaultInitAllocator<U>;
    };
    DefaultInitAllocator() = default;
    template <class U>
    DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// An array's decoded payload bytes.
using PayloadBytes = std::vector<unsigned char, DefaultInitAllocator<unsigned char>>;

std::string sizeMismatch(const ArrayDesc& a, std::uint64_t values, std::uint64_t expected) {
    return a.label + " holds " + std::to_string(values) + " values, expected " +
           std::to_string(expected);
}

/// Claims the appended bytes [start, end) for array a before they are decoded: every DataArray
/// has data of its own (VTK's writers write each once), so bytes that another array already read
/// are refused, whatever the codec. Data reused by many arrays or Pieces would otherwise be
/// decoded again and again from one small block, without bound by the file.
void claimAppended(const XmlDoc& doc, const ArrayDesc& a, std::uint64_t start, std::uint64_t end) {
    end = std::max(end, start + 1);
    auto next = doc.appendedReads.lower_bound(end);
    if (next != doc.appendedReads.begin()) {
        const auto& [prevStart, prev] = *std::prev(next);
        if (prev.first > start)
            throwParseError(doc.file, atByte(start),
                            a.label + " (appended offset " + std::to_string(a.offset) +
                                "): its data (file bytes " + std::to_string(start) + " to " +
                                std::to_string(end) + ") overlap the data of " + prev.second +
                                " (bytes " + std::to_string(prevStart) + " to " +
                                std::to_string(prev.first) +
                                "): each DataArray must have data of its own");
    }
    doc.appendedReads.emplace(start, std::pair{end, a.label});
}

/// Reads an array's binary payload: [nbytes] + data, or, compressed, [nblocks, blockSize,
/// lastBlockSize, compressed sizes...] + blocks (VTK's layout for zlib, LZ4 and LZMA alike).
/// The sizes the header declares must equal what the DataArray declares (expected values), and
/// are charged to the budget, before anything is decompressed; appendedStart (the file offset of
/// appended data) claims the bytes read for this array alone.
PayloadBytes readPayload(const XmlDoc& doc, const ArrayDesc& a, ByteSource& src,
                         std::uint64_t expected, std::optional<std::uint64_t> appendedStart,
                         const ReadOptions& options) {
    const std::size_t hs = doc.headerSize;
    const std::size_t es = scalarSize(*a.type);
    auto fail = [&](const std::string& message) {
        throwParseError(doc.file, atByte(src.fileOffset()), a.label + ": " + message);
    };
    auto header = [&](std::uint64_t count, const char* what) {
        if (count > src.remaining() / hs)
            fail(std::string("the ") + what + " (" + std::to_string(count) + " x " +
                 std::to_string(hs) + " bytes) runs past the end of the data");
        std::vector<unsigned char> raw;
        src.read(static_cast<std::size_t>(count * hs), raw);
        std::vector<std::uint64_t> v(static_cast<std::size_t>(count));
        for (std::size_t i = 0; i < v.size(); ++i)
            v[i] = loadHeaderInt(raw.data() + i * hs, hs, doc.bigEndian);
        return v;
    };
    // The declared sizes first: the header's total must be the DataArray's, so a header cannot
    // make the reader allocate more than the mesh the file declares.
    auto checkTotal = [&](std::uint64_t totalBytes) {
        if (totalBytes % es != 0)
            fail("holds " + std::to_string(totalBytes) + " bytes, not a whole number of " +
                 xmlTypeName(*a.type) + " values");
        if (totalBytes / es != expected)
            throwParseError(doc.file, atByte(src.fileOffset()),
                            sizeMismatch(a, totalBytes / es, expected));
        checkAllocation(doc.file, a.label, totalBytes / es, es, options.maxMemoryBytes);
    };
    // The bytes this array's data span in the file, claimed before decoding.
    auto claim = [&](std::uint64_t sourceBytes) {
        if (!appendedStart) return;
        const std::uint64_t span = src.raw() ? sourceBytes : sourceBytes / 3 * 4;
        claimAppended(doc, a, *appendedStart, src.fileOffset() + span);
    };

    const std::uint64_t maxRatio = maxCompressionRatio(doc.compressor);
    const std::string ratioName = std::string(doc.compressor == VtuCompressor::Lz4    ? "LZ4"
                                              : doc.compressor == VtuCompressor::Lzma ? "LZMA"
                                                                                      : "deflate") +
                                  "'s maximum ratio of " + std::to_string(maxRatio) + ":1";
    const std::string blockName = doc.compressor == VtuCompressor::Lz4    ? "LZ4 block "
                                  : doc.compressor == VtuCompressor::Lzma ? "LZMA block "
                                                                          : "zlib block ";

    PayloadBytes out;
    if (doc.compressor == VtuCompressor::None) {
        const std::uint64_t nbytes = header(1, "size header")[0];
        checkTotal(nbytes);
        if (nbytes > src.remaining())
            fail("declares " + std::to_string(nbytes) + " bytes, but only " +
                 std::to_string(src.remaining()) + " remain");
        claim(nbytes);
        options.budget->charge(doc.file, a.label, nbytes, 1);
        out.resize(static_cast<std::size_t>(nbytes));
        src.readInto(static_cast<std::size_t>(nbytes), out.data());
        return out;
    }
    const std::vector<std::uint64_t> h = header(3, "compression header");
    const std::uint64_t blocks = h[0], blockSize = h[1], lastSize = h[2];
    const std::vector<std::uint64_t> sizes = header(blocks, "table of compressed block sizes");
    if (blocks > 0 && (blockSize == 0 || lastSize > blockSize))
        fail("invalid compression header: block size " + std::to_string(blockSize) +
             ", last block size " + std::to_string(lastSize));
    std::uint64_t total = 0, compressedTotal = 0;
    if (blocks > 0) {
        if (blocks - 1 > std::numeric_limits<std::uint64_t>::max() / 2 / blockSize)
            fail("compression header declares an absurd size");
        total = (blocks - 1) * blockSize + (lastSize == 0 ? blockSize : lastSize);
    }
    for (std::uint64_t s : sizes) {
        compressedTotal += s;
        if (compressedTotal < s) fail("compressed block sizes overflow");
    }
    checkTotal(total);
    if (compressedTotal > src.remaining())
        fail("compressed blocks of " + std::to_string(compressedTotal) + " bytes run past the " +
             "end of the data (" + std::to_string(src.remaining()) + " bytes remain)");
    // Checked block by block before allocating: a block of s bytes expands to at most
    // maxRatio * s.
    for (std::uint64_t b = 0; b < blocks; ++b) {
        const std::uint64_t expect = (b + 1 == blocks && lastSize != 0) ? lastSize : blockSize;
        if (expect > sizes[b] * maxRatio)  // sizes[b] <= remaining(): no overflow
            fail(blockName + std::to_string(b) + " of " + std::to_string(blocks) + ": " +
                 std::to_string(sizes[b]) + " compressed bytes cannot inflate to the " +
                 std::to_string(expect) + " bytes the header declares (at most " +
                 std::to_string(sizes[b] * maxRatio) + " at " + ratioName + ")");
    }
    claim(compressedTotal);
    options.budget->charge(doc.file, a.label, total, 1);
    out.resize(static_cast<std::size_t>(total));  // not zero-filled: only decoded bytes touch it
    std::vector<unsigned char> block;
    for (std::uint64_t b = 0; b < blocks; ++b) {
        const std::uint64_t expect = (b + 1 == blocks && lastSize != 0) ? lastSize : blockSize;
        block.clear();
        src.read(static_cast<std::size_t>(sizes[b]), block);
        const std::string problem =
            decompressBlock(doc.compressor, block.data(), block.size(), out.data() + b * blockSize,
                            static_cast<std::size_t>(expect), doc.file);
        if (!problem.empty())
            fail(blockName + std::to_string(b) + " of DataArray '" + a.name + "' is corrupt (" +
                 problem + ")");
    }
    return out;
}

// ---- ascii payloads ----

template <class T>
std::vector<T> parseAscii(const XmlDoc& doc, const ArrayDesc& a,
                          std::optional<std::uint64_t> expected, const ReadOptions& options) {
    const std::string& s = a.text;
    auto isSpace = [](char c) { return c == ' ' || c == '\n' || c == '\t' || c == '\r'; };
    // Count first, so a wrong count is refused before allocating.
    std::uint64_t count = 0;
    for (std::size_t i = 0; i < s.size();) {
        while (i < s.size() && isSpace(s[i])) ++i;
        if (i >= s.size()) break;
        ++count;
        while (i < s.size() && !isSpace(s[i])) ++i;
    }
    if (expected && count != *expected)
        throwParseError(doc.file, atLine(a.line), sizeMismatch(a, count, *expected));
    checkAllocation(doc.file, a.label, count, sizeof(T), options.maxMemoryBytes);
    options.budget->charge(doc.file, a.label, count, sizeof(T));
    std::vector<T> out;
    out.reserve(static_cast<std::size_t>(count));
    const bool integer = isIntegerType(*a.type);
    std::uint64_t line = a.textLine;
    for (std::size_t i = 0; i < s.size();) {
        while (i < s.size() && isSpace(s[i])) line += s[i++] == '\n';
        if (i >= s.size()) break;
        std::size_t j = i;
        while (j < s.size() && !isSpace(s[j])) ++j;
        const std::string_view token(s.data() + i, j - i);
        bool ok = false;
        T value{};
        if (integer) {
            if (const std::optional<std::int64_t> v = parseVtkInteger(token)) {
                ok = true;
                value = static_cast<T>(*v);
            } else if (const std::optional<std::uint64_t> u = parseVtkCount(token)) {
                ok = true;
                value = static_cast<T>(*u);
            }
        } else if (const std::optional<double> d = parseVtkReal(token)) {
            ok = true;
            if constexpr (std::is_integral_v<T>) {
                ok = *d >= -9.2e18 && *d <= 9.2e18;
                value = ok ? static_cast<T>(*d) : T{};
            } else {
                value = static_cast<T>(*d);
            }
        }
        if (!ok)
            throwParseError(doc.file, atLine(line),
                            a.label + ": expected " +
                                (integer ? std::string("an integer") : std::string("a number")) +
                                " (" + xmlTypeName(*a.type) + "), got '" +
                                std::string(s.data() + i, std::min<std::size_t>(j - i, 40)) + "'");
        out.push_back(value);
        i = j;
    }
    return out;
}

// ---- arrays of any encoding ----

/// Converts raw file values of type S (byte-swapped when swap) to T; float -> integer conversions
/// outside the int64 range become -1, which index checks reject.
template <class T, class S>
std::vector<T> convertValues(const PayloadBytes& raw, bool swap, const XmlDoc& doc,
                             const ArrayDesc& a, const ReadOptions& options) {
    const std::size_t count = raw.size() / sizeof(S);
    checkAllocation(doc.file, a.label, count, sizeof(T), options.maxMemoryBytes);
    options.budget->charge(doc.file, a.label, count, sizeof(T));
    std::vector<T> out(count);
    unsigned char buf[sizeof(S)];
    for (std::size_t i = 0; i < count; ++i) {
        const unsigned char* src = raw.data() + i * sizeof(S);
        if (swap && sizeof(S) > 1) {
            for (std::size_t k = 0; k < sizeof(S); ++k) buf[k] = src[sizeof(S) - 1 - k];
            src = buf;
        }
        S v;
        std::memcpy(&v, src, sizeof(S));
        if constexpr (std::is_integral_v<T> && std::is_floating_point_v<S>)
            out[i] = (v >= -9.2e18 && v <= 9.2e18) ? static_cast<T>(v) : T(-1);
        else
            out[i] = static_cast<T>(v);
    }
    options.budget->release(raw.size());  // the caller frees raw on return
    return out;
}

/// Within this file a reader's options.progress hears the encoded bytes of each array decoded
/// (ArrayDesc::encodedBytes), not a fraction: readVtuFile's wrapper turns them into one.
template <class T>
std::vector<T> decodeArray(const std::vector<char>& bytes, const XmlDoc& doc, const ArrayDesc& a,
                           std::uint64_t expected, const ReadOptions& options);

template <class T>
std::vector<T> readArray(const std::vector<char>& bytes, const XmlDoc& doc, const ArrayDesc& a,
                         std::uint64_t expected, const ReadOptions& options) {
    std::vector<T> out = decodeArray<T>(bytes, doc, a, expected, options);
    if (options.progress) options.progress(double(a.encodedBytes));
    return out;
}

template <class T>
std::vector<T> decodeArray(const std::vector<char>& bytes, const XmlDoc& doc, const ArrayDesc& a,
                           std::uint64_t expected, const ReadOptions& options) {
    if (a.encoding == Encoding::Ascii) return parseAscii<T>(doc, a, expected, options);
    PayloadBytes raw;
    if (a.encoding == Encoding::Binary) {
        ByteSource src(a.text, Base64Origin{doc.file, a.textByte, a.label});
        raw = readPayload(doc, a, src, expected, std::nullopt, options);
    } else {
        if (!doc.hasAppended)
            throwParseError(doc.file, atLine(a.line),
                            a.label + ": format=\"appended\" but the file has no AppendedData");
        const std::uint64_t size = doc.appendedEnd - doc.appendedStart;
        if (a.offset >= size)
            throwParseError(doc.file, atLine(a.line),
                            a.label + ": offset " + std::to_string(a.offset) +
                                " lies beyond the appended data of " + std::to_string(size) +
                                " bytes");
        const std::uint64_t start = doc.appendedStart + a.offset;
        const std::size_t n = static_cast<std::size_t>(doc.appendedEnd - start);
        const std::string label = a.label + " (appended offset " + std::to_string(a.offset) + ")";
        if (doc.appendedBase64) {
            ByteSource src(std::string_view(bytes.data() + start, n),
                           Base64Origin{doc.file, start, label});
            raw = readPayload(doc, a, src, expected, start, options);
        } else {
            ByteSource src(bytes.data() + start, n, start);
            raw = readPayload(doc, a, src, expected, start, options);
        }
    }
    const bool swap = doc.bigEndian == hostIsLittleEndian();
    switch (*a.type) {
        case ScalarType::Int8:
            return convertValues<T, std::int8_t>(raw, swap, doc, a, options);
        case ScalarType::UInt8:
            return convertValues<T, std::uint8_t>(raw, swap, doc, a, options);
        case ScalarType::Int16:
            return convertValues<T, std::int16_t>(raw, swap, doc, a, options);
        case ScalarType::UInt16:
            return convertValues<T, std::uint16_t>(raw, swap, doc, a, options);
        case ScalarType::Int32:
            return convertValues<T, std::int32_t>(raw, swap, doc, a, options);
        case ScalarType::UInt32:
            return convertValues<T, std::uint32_t>(raw, swap, doc, a, options);
        case ScalarType::Int64:
            return convertValues<T, std::int64_t>(raw, swap, doc, a, options);
        case ScalarType::UInt64:
            return convertValues<T, std::uint64_t>(raw, swap, doc, a, options);
        case ScalarType::Float32:
            return convertValues<T, float>(raw, swap, doc, a, options);
        case ScalarType::Float64:
            return convertValues<T, double>(raw, swap, doc, a, options);
    }
    return {};
}

constexpr std::int64_t kVtkPolyhedron = 42;

/// Points, cells (VtkCellArrays convention) and fields of all Pieces, point indices offset.
struct RawGrid {
    std::vector<Vec3f> points;
    VtkCellArrays cells;
    std::vector<Field> fields;
};

const ArrayDesc* findArray(const PieceDesc& p, Section section, const std::string& name) {
    for (const ArrayDesc& a : p.arrays)
        if (a.section == section && (name.empty() || a.name == name)) return &a;
    return nullptr;
}

std::string fieldKey(const Field& f) {
    return std::string(associationName(f.association)) + " DataArray '" + f.name + "'";
}

/// Association and name of a field as one map key.
std::string fieldId(const Field& f) {
    return (f.association == Association::Point ? "p" : "c") + f.name;
}

/// The first field of each association and name, for merging Pieces in linear time.
template <class F>
std::unordered_map<std::string, F*> indexFields(std::vector<F>& fields) {
    std::unordered_map<std::string, F*> index;
    index.reserve(fields.size());
    for (F& f : fields) index.emplace(fieldId(f), &f);
    return index;
}

/// Appends a Piece's polyhedron face streams to out.faces and its cells' stream ranges to
/// out.faceOffsets (padded for the cells of earlier Pieces). VTK 9.1's layout: `faces` holds the
/// streams [nFaces, n0, ids..., n1, ids...] of the polyhedra one after another, `faceoffsets`
/// per cell the end of its stream, or -1 for a cell other than a polyhedron (VTK's reader reads
/// the streams in order and checks only where the last one ends; uvr checks each).
void readFaceStreams(const std::vector<char>& bytes, const XmlDoc& doc, const PieceDesc& p,
                     const std::string& label, const std::vector<std::int64_t>& types,
                     std::uint64_t pointBase, const ReadOptions& options, VtkCellArrays& out) {
    const ArrayDesc* facesA = findArray(p, Section::Cells, "faces");
    const ArrayDesc* endsA = findArray(p, Section::Cells, "faceoffsets");
    if (!facesA || !endsA || !facesA->type || !endsA->type)
        throwParseError(doc.file, atLine(p.line),
                        label +
                            ": polyhedron cells (type 42) need numeric <Cells> DataArrays "
                            "'faces' and 'faceoffsets' (VTK 9.1's layout; the later "
                            "'face_connectivity' layout is not read)");
    const std::vector<std::int64_t> ends =
        readArray<std::int64_t>(bytes, doc, *endsA, p.cells, options);
    while (out.faceOffsets.size() < out.types.size() + 1)
        out.faceOffsets.push_back(static_cast<std::int64_t>(out.faces.size()));
    const std::int64_t faceBase = static_cast<std::int64_t>(out.faces.size());
    options.budget->charge(doc.file, label + ": face offsets", p.cells, sizeof(std::int64_t));
    std::int64_t previous = 0;
    for (std::size_t c = 0; c < ends.size(); ++c) {
        const std::string cell = "cell " + std::to_string(c);
        if (types[c] == kVtkPolyhedron) {
            if (ends[c] < previous)
                throwParseError(doc.file, atLine(endsA->line),
                                endsA->label + ": " + cell + " (polyhedron): end offset " +
                                    std::to_string(ends[c]) +
                                    " lies before the end of the previous face stream, " +
                                    std::to_string(previous));
            previous = ends[c];
        } else if (ends[c] != -1 && ends[c] != previous) {
            throwParseError(doc.file, atLine(endsA->line),
                            endsA->label + ": " + cell + " (VTK type " + std::to_string(types[c]) +
                                ") is no polyhedron, expected -1, got " + std::to_string(ends[c]));
        }
        out.faceOffsets.push_back(faceBase + previous);
    }
    std::vector<std::int64_t> faces =
        readArray<std::int64_t>(bytes, doc, *facesA, static_cast<std::uint64_t>(previous), options);
    // Point indices of later Pieces are offset like the connectivity's (walking each stream
    // by its face sizes; appendVtkCells checks the streams).
    if (pointBase > 0)
        for (std::size_t c = 0, b = 0; c < ends.size(); ++c) {
            if (types[c] != kVtkPolyhedron) continue;
            const std::size_t e = static_cast<std::size_t>(ends[c]);
            for (std::size_t k = b + 1; k < e;) {
                const std::int64_t n = faces[k];
                if (n < 0 || static_cast<std::uint64_t>(n) >= e - k) break;
                for (std::size_t j = k + 1; j <= k + static_cast<std::size_t>(n); ++j)
                    if (faces[j] >= 0) faces[j] += static_cast<std::int64_t>(pointBase);
                k += static_cast<std::size_t>(n) + 1;
            }
            b = e;
        }
    options.budget->charge(doc.file, label + ": faces", faces.size(), sizeof(std::int64_t));
    out.faces.insert(out.faces.end(), faces.begin(), faces.end());
    options.budget->release((ends.size() + faces.size()) * sizeof(std::int64_t));
}

void readPiece(const std::vector<char>& bytes, const XmlDoc& doc, std::size_t index,
               const ReadOptions& options, RawGrid& grid) {
    const PieceDesc& p = doc.pieces[index];
    const std::string label = "Piece " + std::to_string(index);
    auto require = [&](Section section, const std::string& name) -> const ArrayDesc& {
        const ArrayDesc* a = findArray(p, section, name);
        if (!a)
            throwParseError(doc.file, atLine(p.line),
                            label + ": missing " +
                                (section == Section::Points ? std::string("<Points> DataArray")
                                                            : "<Cells> DataArray '" + name + "'"));
        if (!a->type)
            throwParseError(doc.file, atLine(a->line), a->label + ": expected a numeric type");
        return *a;
    };
    const std::uint64_t pointBase = grid.points.size();

    // Points.
    if (p.points > 0 || findArray(p, Section::Points, "")) {
        const ArrayDesc& a = require(Section::Points, "");
        if (a.components != 3)
            throwParseError(doc.file, atLine(a.line),
                            a.label + ": expected NumberOfComponents=\"3\", got " +
                                std::to_string(a.components));
        const std::vector<float> xyz = readArray<float>(bytes, doc, a, p.points * 3, options);
        // Checked after reading, so that counts the file cannot hold are reported as such.
        if (pointBase + p.points > std::numeric_limits<std::uint32_t>::max())
            throwError(ErrorKind::Unsupported, doc.file,
                       label + ": more than 4294967295 points in all are not supported");
        options.budget->charge(doc.file, label + ": points", p.points, sizeof(Vec3f));
        if (index == 0) grid.points.reserve(p.points);
        for (std::size_t i = 0; i < p.points; ++i)
            grid.points.emplace_back(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
        options.budget->release(xyz.size() * sizeof(float));
    }

    // Cells: VTK XML offsets are END offsets; VtkCellArrays wants n + 1 starting at 0.
    if (p.cells > 0) {
        const ArrayDesc& offA = require(Section::Cells, "offsets");
        const ArrayDesc& typeA = require(Section::Cells, "types");
        const ArrayDesc& connA = require(Section::Cells, "connectivity");
        const std::vector<std::int64_t> ends =
            readArray<std::int64_t>(bytes, doc, offA, p.cells, options);
        std::int64_t previous = 0;
        for (std::size_t c = 0; c < ends.size(); ++c) {
            if (ends[c] < previous)
                throwParseError(doc.file, atLine(offA.line),
                                offA.label + ": end offset " + std::to_string(ends[c]) +
                                    " of cell " + std::to_string(c) +
                                    " is below the previous offset " + std::to_string(previous));
            previous = ends[c];
        }
        const std::vector<std::int64_t> types =
            readArray<std::int64_t>(bytes, doc, typeA, p.cells, options);
        // What the cells can list, before the connectivity is read: a 3D cell (of any order,
        // or a polyhedron) lists distinct points, so no more than the Piece declares.
        for (std::size_t c = 0; c < types.size(); ++c) {
            const std::int64_t nodes = ends[c] - (c == 0 ? 0 : ends[c - 1]);
            if (types[c] < 0 || types[c] > 255 || static_cast<std::uint64_t>(nodes) <= p.points)
                continue;
            const VtkCellTypeInfo info = vtkCellTypeInfo(static_cast<int>(types[c]));
            if (info.volumetric || types[c] == kVtkPolyhedron)
                throwParseError(doc.file, atLine(offA.line),
                                offA.label + ": cell " + std::to_string(c) + " (" + info.name +
                                    ") lists " + std::to_string(nodes) + " nodes, more than the " +
                                    std::to_string(p.points) + " points of its Piece");
        }
        const std::vector<std::int64_t> conn = readArray<std::int64_t>(
            bytes, doc, connA, static_cast<std::uint64_t>(ends.back()), options);
        VtkCellArrays& out = grid.cells;
        options.budget->charge(doc.file, label + ": cells", types.size(),
                               sizeof(std::int32_t) + sizeof(std::int64_t));
        options.budget->charge(doc.file, label + ": connectivity", conn.size(),
                               sizeof(std::int64_t));
        const std::int64_t connBase = static_cast<std::int64_t>(out.connectivity.size());
        if (out.offsets.empty()) out.offsets.push_back(0);
        if (std::find(types.begin(), types.end(), kVtkPolyhedron) != types.end())
            readFaceStreams(bytes, doc, p, label, types, pointBase, options, out);
        for (std::size_t c = 0; c < types.size(); ++c) {
            if (types[c] < 0 || types[c] > 255)
                throwParseError(doc.file, atLine(typeA.line),
                                typeA.label + ": cell " + std::to_string(c) +
                                    ": expected a VTK cell type in [0, 255], got " +
                                    std::to_string(types[c]));
            out.types.push_back(static_cast<std::int32_t>(types[c]));
            out.offsets.push_back(connBase + ends[c]);
        }
        out.connectivity.reserve(out.connectivity.size() + conn.size());
        for (std::int64_t id : conn)
            out.connectivity.push_back(id < 0 ? id : id + static_cast<std::int64_t>(pointBase));
        options.budget->release((ends.size() + types.size() + conn.size()) * sizeof(std::int64_t));
    }

    // Point and cell fields, concatenated across Pieces by name and association.
    std::vector<Field> fields;
    for (const ArrayDesc& a : p.arrays) {
        if (a.section != Section::PointData && a.section != Section::CellData) continue;
        if (!a.type) continue;  // String arrays
        if (a.name.empty())
            throwParseError(doc.file, atLine(a.line), a.label + ": expected a Name attribute");
        Field f;
        f.name = a.name;
        f.association = a.section == Section::PointData ? Association::Point : Association::Cell;
        f.components = static_cast<int>(a.components);
        const std::uint64_t tuples = f.association == Association::Point ? p.points : p.cells;
        if (tuples > std::numeric_limits<std::uint64_t>::max() / a.components)
            throwParseError(doc.file, atLine(a.line), a.label + ": absurd size");
        f.values = readArray<float>(bytes, doc, a, tuples * a.components, options);
        fields.push_back(std::move(f));
    }
    if (index == 0) {
        grid.fields = std::move(fields);
        return;
    }
    const auto pieceFields = indexFields(fields);
    for (const Field& f : grid.fields) {
        const auto found = pieceFields.find(fieldId(f));
        if (found == pieceFields.end())
            throwParseError(doc.file, atLine(p.line),
                            label + " has no " + fieldKey(f) + ", which Piece 0 has");
        const Field* it = found->second;
        if (it->components != f.components)
            throwParseError(doc.file, atLine(p.line),
                            label + ": " + fieldKey(f) + " has " + std::to_string(it->components) +
                                " components, Piece 0 has " + std::to_string(f.components));
    }
    const auto gridFields = indexFields(grid.fields);
    for (Field& g : fields) {
        const auto found = gridFields.find(fieldId(g));
        if (found == gridFields.end())
            throwParseError(doc.file, atLine(p.line),
                            label + " has " + fieldKey(g) + ", which Piece 0 lacks");
        Field* it = found->second;
        options.budget->charge(doc.file, label + ": " + fieldKey(g), g.values.size(),
                               sizeof(float));
        it->values.insert(it->values.end(), g.values.begin(), g.values.end());
    }
    for (const Field& g : fields) options.budget->release(g.values.size() * sizeof(float));
}

Mesh readVtuFile(const std::string& path, const ReadOptions& options, bool allowParallel);

/// Checks before decoding anything that the mesh the file declares fits the budget: every
/// Piece's points (3 x float), cells (a type and an offset) and field values (float), which
/// the reader holds all at once before converting the cells. What a file can make the reader
/// allocate follows from these counts (every array's decoded size must equal its declared size),
/// not from its size or its codec.
void checkDeclaredMesh(const XmlDoc& doc, const LoadBudget& budget) {
    constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
    auto add = [](std::uint64_t& sum, std::uint64_t count, std::uint64_t size) {
        const std::uint64_t bytes = size != 0 && count > kMax / size ? kMax : count * size;
        sum = sum > kMax - bytes ? kMax : sum + bytes;
    };
    std::uint64_t bytes = 0, points = 0, cells = 0, values = 0;
    for (const PieceDesc& p : doc.pieces) {
        add(points, p.points, 1);
        add(cells, p.cells, 1);
        for (const ArrayDesc& a : p.arrays)
            if (a.type && (a.section == Section::PointData || a.section == Section::CellData)) {
                std::uint64_t n = 0;
                add(n, a.section == Section::PointData ? p.points : p.cells, a.components);
                add(values, n, 1);
            }
    }
    add(bytes, points, sizeof(Vec3f));
    add(bytes, cells, sizeof(std::int32_t) + sizeof(std::int64_t));
    add(bytes, values, sizeof(float));
    budget.check(doc.file,
                 "the mesh it declares (" + std::to_string(points) + " points, " +
                     std::to_string(cells) + " cells and " + std::to_string(values) +
                     " field values in " + std::to_string(doc.pieces.size()) + " Pieces)",
                 bytes, 1);
}

/// Reads a .pvtu's pieces [first, end) (all: the defaults) into one mesh; every listed piece is
/// checked first. counts, when given, receives each piece read's points and cells.
Mesh readPvtuFile(const std::string& path, const XmlDoc& doc, const ReadOptions& options,
                  std::size_t firstPiece = 0, std::size_t endPiece = SIZE_MAX,
                  std::vector<std::pair<std::uint64_t, std::uint64_t>>* counts = nullptr) {
    if (doc.pieces.empty()) throwParseError(path, atByte(0), "expected <Piece Source=...> entries");
    const std::size_t end = std::min(endPiece, doc.pieces.size());
    namespace fs = std::filesystem;
    const fs::path folder = fs::path(path).parent_path();
    // Every piece's file, checked before reading any: not the .pvtu itself, and each file once
    // (one piece listed many times would multiply the load).
    std::vector<std::string> piecePaths;
    std::map<std::string, std::size_t> firstListing;  // canonical path -> piece index
    for (std::size_t k = 0; k < doc.pieces.size(); ++k) {
        const PieceDesc& p = doc.pieces[k];
        const fs::path source = fs::path(p.source);
        piecePaths.push_back((source.is_absolute() ? source : folder / source).string());
        const std::string label = "Piece " + std::to_string(k) + " ('" + p.source + "')";
        if (sameFile(piecePaths.back(), path))
            throwParseError(path, atLine(p.line), label + " names the .pvtu file itself");
        // The same file by inode (hard links too), else by canonical path.
        struct stat info {};
        std::string key;
        if (::stat(piecePaths.back().c_str(), &info) == 0) {
            key = std::to_string(info.st_dev) + ":" + std::to_string(info.st_ino);
        } else {
            std::error_code ec;
            const fs::path canonical = fs::weakly_canonical(fs::path(piecePaths.back()), ec);
            key = ec ? piecePaths.back() : canonical.string();
        }
        const auto [first, fresh] = firstListing.emplace(key, k);
        if (!fresh)
            throwParseError(path, atLine(p.line),
                            label + " is listed twice: Piece " + std::to_string(first->second) +
                                " (line " + std::to_string(doc.pieces[first->second].line) +
                                ") names the same file");
    }
    LoadBudget& budget = *options.budget;
    const std::uint64_t heldBefore = budget.used();
    Mesh mesh;
    for (std::size_t k = firstPiece; k < end; ++k) {
        const PieceDesc& p = doc.pieces[k];
        const std::string& piecePath = piecePaths[k];
        const std::string label = "Piece " + std::to_string(k) + " ('" + p.source + "')";
        // A piece is a dataset: a .pvtu or a .pvd there could recurse (ParaView reads only
        // UnstructuredGrid pieces).
        const MeshFormat format = sniffMeshFormat(piecePath);
        if (format == MeshFormat::Pvtu || format == MeshFormat::Pvd)
            throwError(ErrorKind::Unsupported, path,
                       atLine(p.line) + ": " + label + ": " + piecePath + " is " +
                           (format == MeshFormat::Pvd ? "a ParaView collection (.pvd)"
                                                      : "a PUnstructuredGrid (.pvtu)") +
                           "; a .pvtu piece must be an UnstructuredGrid .vtu file");
        ReadOptions pieceOptions = options;  // progress: piece k's fraction of the whole
        if (options.progress)
            pieceOptions.progress = [k = k - firstPiece, n = end - firstPiece,
                                     outer = options.progress](double f) {
                outer((double(k) + f) / double(n));
            };
        Mesh piece = readVtuFile(piecePath, pieceOptions, false);
        budget.charge(path, label, meshBytes(piece), 1);  // its copy in the merged mesh
        if (counts) counts->emplace_back(piece.pointCount(), piece.cellCount());
        appendMeshPiece(mesh, piece, k == firstPiece, path, atLine(p.line), label);
        budget.resetTo(heldBefore + meshBytes(mesh));  // the piece is freed next
    }
    return mesh;
}

Mesh readVtuFile(const std::string& path, const ReadOptions& options, bool allowParallel) {
    LoadBudget& budget = *options.budget;
    const std::uint64_t heldBefore = budget.used();
    const std::vector<char> bytes = readFileCharged(path, budget);
    const XmlDoc doc = parseXml(path, bytes);
    std::uint64_t textBytes = 0;
    for (const PieceDesc& p : doc.pieces)
        for (const ArrayDesc& a : p.arrays) textBytes += a.text.size();
    budget.charge(path, "the inline DataArray text", textBytes, 1);
    if (doc.type == "PUnstructuredGrid") {
        if (!allowParallel)
            throwError(ErrorKind::Unsupported, path,
                       "is a PUnstructuredGrid (.pvtu); a .pvtu piece must be an "
                       "UnstructuredGrid .vtu file");
        Mesh mesh = readPvtuFile(path, doc, options);
        budget.resetTo(heldBefore + meshBytes(mesh));  // the file is freed on return
        return mesh;
    }
    if (doc.pieces.empty())
        throwParseError(path, atByte(0),
                        "expected at least one <Piece NumberOfPoints=... NumberOfCells=...>");
    checkDeclaredMesh(doc, budget);
    // Progress: the fraction of the arrays' encoded bytes decoded (decoding, zlib's above all,
    // is most of a large file's read).
    ReadOptions local = options;
    if (options.progress) {
        std::uint64_t total = 0;
        for (const PieceDesc& p : doc.pieces)
            for (const ArrayDesc& a : p.arrays) total += a.encodedBytes;
        auto done = std::make_shared<double>(0.0);
        local.progress = [done, total, outer = options.progress](double arrayBytes) {
            *done += arrayBytes;
            outer(total > 0 ? std::min(1.0, *done / double(total)) : 1.0);
        };
    }
    RawGrid grid;
    for (std::size_t k = 0; k < doc.pieces.size(); ++k) readPiece(bytes, doc, k, local, grid);
    Mesh mesh;
    mesh.points = std::move(grid.points);
    mesh.fields = std::move(grid.fields);
    if (grid.cells.offsets.empty()) grid.cells.offsets.push_back(0);
    grid.cells.polyhedronFaces = PolyhedronFaces::Separate;
    while (grid.cells.faceOffsets.size() < grid.cells.types.size() + 1)
        grid.cells.faceOffsets.push_back(static_cast<std::int64_t>(grid.cells.faces.size()));
    budget.charge(path, "the cells", grid.cells.types.size(),
                  sizeof(CellType) + sizeof(std::uint64_t));
    budget.charge(path, "the cell connectivity", grid.cells.connectivity.size(),
                  sizeof(std::uint32_t));
    appendVtkCells(grid.cells, mesh, path, &budget);
    budget.resetTo(heldBefore + meshBytes(mesh));  // the file and the raw cells are freed next
    return mesh;
}

}  // namespace

Mesh readVtu(const std::string& path, const ReadOptions& options) {
    const BudgetedOptions budgeted(options);
    return readVtuFile(path, budgeted.options(), true);
}

Mesh readPvtu(const std::string& path, const ReadOptions& options) {
    const BudgetedOptions budgeted(options);
    LoadBudget& budget = budgeted.budget();
    const std::uint64_t heldBefore = budget.used();
    const std::vector<char> bytes = readFileCharged(path, budget);
    const XmlDoc doc = parseXml(path, bytes);
    if (doc.type != "PUnstructuredGrid")
        throwError(ErrorKind::Unsupported, path,
                   "VTKFile type '" + doc.type + "' is not a PUnstructuredGrid (.pvtu)");
    Mesh mesh = readPvtuFile(path, doc, budgeted.options());
    budget.resetTo(heldBefore + meshBytes(mesh));
    return mesh;
}

std::size_t pvtuPieceCount(const std::string& path) {
    LoadBudget budget(0);
    const std::vector<char> bytes = readFileCharged(path, budget);
    const XmlDoc doc = parseXml(path, bytes);
    if (doc.type != "PUnstructuredGrid")
        throwError(ErrorKind::Unsupported, path,
                   "VTKFile type '" + doc.type + "' is not a PUnstructuredGrid (.pvtu)");
    return doc.pieces.size();
}

MeshPart readPvtuPart(const std::string& path, std::size_t firstPiece, std::size_t endPiece,
                      const ReadOptions& options) {
    const BudgetedOptions budgeted(options);
    const std::vector<char> bytes = readFileCharged(path, budgeted.budget());
    const XmlDoc doc = parseXml(path, bytes);
    if (doc.type != "PUnstructuredGrid")
        throwError(ErrorKind::Unsupported, path,
                   "VTKFile type '" + doc.type + "' is not a PUnstructuredGrid (.pvtu)");
    if (firstPiece >= endPiece || endPiece > doc.pieces.size())
        throwError(ErrorKind::Argument, path,
                   "pieces [" + std::to_string(firstPiece) + ", " + std::to_string(endPiece) +
                       ") asked for, but the file lists " + std::to_string(doc.pieces.size()));
    std::vector<std::pair<std::uint64_t, std::uint64_t>> counts;
    MeshPart part;
    part.mesh = readPvtuFile(path, doc, budgeted.options(), firstPiece, endPiece, &counts);
    // Ids in the whole file's order (its pieces concatenated, as readPvtu merges them): the
    // piece's index above kPieceIdShift bits, the point's or cell's in the piece below.
    for (std::size_t k = 0; k < counts.size(); ++k) {
        const std::uint64_t base = std::uint64_t(firstPiece + k) << kPieceIdShift;
        for (std::uint64_t i = 0; i < counts[k].first; ++i) part.pointIds.push_back(base | i);
        for (std::uint64_t c = 0; c < counts[k].second; ++c) part.cellIds.push_back(base | c);
    }
    return part;
}

}  // namespace uvr
