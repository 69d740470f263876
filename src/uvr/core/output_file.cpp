// SPDX-License-Identifier: MIT
#include "uvr/core/output_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "uvr/core/error.h"
#include "uvr/core/file_util.h"

namespace uvr {

namespace {

namespace fs = std::filesystem;

constexpr std::size_t kBufferBytes = 1 << 20;
constexpr int kMaxSymlinks = 40;

[[noreturn]] void ioError(const std::string& path, const std::string& what, int err) {
    throwError(ErrorKind::Io, path, what + ": " + std::strerror(err));
}

// Step: the registry of uncommitted temporaries, read by signal handlers. A slot's state is 0
// (free), 1 (being filled) or 2 (holds a temporary's path); only state 2 is read by a handler.
constexpr int kSlots = 64;
constexpr std::size_t kSlotPathBytes = 4096;
struct PendingSlot {
    std::atomic<int> state{0};
    char path[kSlotPathBytes];
};
PendingSlot gPending[kSlots];

int registerPending(const std::string& path) {
    if (path.size() >= kSlotPathBytes) return -1;
    for (int i = 0; i < kSlots; ++i) {
        int expected = 0;
        if (gPending[i].state.compare_exchange_strong(expected, 1)) {
            std::memcpy(gPending[i].path, path.c_str(), path.size() + 1);
            gPending[i].state.store(2);
            return i;
        }
    }
    return -1;  // more than kSlots outputs at once: removed by the destructor only
}

void unregisterPending(int slot) {
    if (slot >= 0) gPending[slot].state.store(0);
}

std::atomic<bool> gHandling{false};

void onTerminatingSignal(int sig) {
    if (!gHandling.exchange(true)) removePendingOutputs();
    ::signal(sig, SIG_DFL);
    ::raise(sig);
}

/// Folder of a path for creating siblings ("." for a bare name).
std::string folderOf(const std::string& path) {
    const std::string folder = fs::path(path).parent_path().string();
    return folder.empty() ? "." : folder;
}

/// Opens a connected stream socket to a Unix socket path.
int connectSocket(const std::string& path, const std::string& shown) {
    sockaddr_un addr{};
    if (path.size() >= sizeof addr.sun_path)
        throwError(ErrorKind::Io, shown, "cannot write: the socket path is too long");
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) ioError(shown, "cannot write to the socket", errno);
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
        const int err = errno;
        ::close(fd);
        ioError(shown, "cannot connect to the socket", err);
    }
    return fd;
}

/// Identity of an existing file (device and inode, following links), or false.
bool fileIdentity(const std::string& path, dev_t& dev, ino_t& ino, mode_t* mode = nullptr) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) return false;
    dev = st.st_dev;
    ino = st.st_ino;
    if (mode) *mode = st.st_mode;
    return true;
}

/// The kernel's rule for shared folders (fs.protected_symlinks, fs.protected_regular and
/// fs.protected_fifos), applied here since uvr follows the links itself: in a folder that is
/// sticky and writable by everyone (/tmp), a symbolic link is followed, and an existing file
/// replaced or written, only when it belongs to the current effective user or to the folder's
/// owner. Anything else may have been planted by another user to redirect the output. Throws
/// Error(Io) naming the entry, its owner and the folder.
void checkSharedFolderEntry(const std::string& shown, const std::string& entry,
                            const struct stat& st) {
    const std::string folder = folderOf(entry);
    struct stat dir;
    if (::stat(folder.c_str(), &dir) != 0)
        ioError(shown, "cannot write: folder '" + folder + "'", errno);
    if ((dir.st_mode & (S_ISVTX | S_IWOTH)) != (S_ISVTX | S_IWOTH)) return;
    if (st.st_uid == ::geteuid() || st.st_uid == dir.st_uid) return;
    const bool link = S_ISLNK(st.st_mode);
    throwError(ErrorKind::Io, shown,
               std::string(link ? "refusing to follow the symbolic link '"
                                : "refusing to replace or write '") +
                   entry + "' owned by " + describeUser(st.st_uid) + " in the shared folder '" +
                   folder + "' (sticky, writable by everyone, owned by " +
                   describeUser(dir.st_uid) +
                   "): another user may have planted it; remove it or name another output");
}

}  // namespace

OutputTarget resolveOutput(const std::string& path) {
    OutputTarget t;
    t.path = path;
    if (path.empty()) throwError(ErrorKind::Argument, "", "empty output file name");
    // Step 1: standard output.
    if (path == "-") {
        t.target = "-";
        t.kind = OutputKind::Stream;
        if (::isatty(STDOUT_FILENO))
            throwError(ErrorKind::Argument, "-",
                       "standard output is a terminal: redirect it to a file or a pipe, or name "
                       "an output file");
        return t;
    }
    // Step 2: follow symbolic links to the file they name; it is written, the links stay.
    std::string p = path;
    struct stat st;
    bool exists = false;
    for (int hops = 0;; ++hops) {
        if (::lstat(p.c_str(), &st) != 0) {
            if (errno != ENOENT) ioError(path, "cannot write", errno);
            break;
        }
        // Every link of the chain and the file it ends at pass the shared-folder rule.
        checkSharedFolderEntry(path, p, st);
        if (!S_ISLNK(st.st_mode)) {
            exists = true;
            break;
        }
        if (hops == kMaxSymlinks)
            throwError(ErrorKind::Io, path, "cannot write: too many levels of symbolic links");
        std::error_code ec;
        fs::path link = fs::read_symlink(p, ec);
        if (ec) throwError(ErrorKind::Io, path, "cannot read the symbolic link: " + ec.message());
        p = link.is_absolute() ? link.string() : (fs::path(p).parent_path() / link).string();
    }
    t.target = p;
    t.exists = exists;
    // Step 3: what the target is.
    if (exists) {
        if (S_ISDIR(st.st_mode)) throwError(ErrorKind::Io, path, "cannot write: is a folder");
        if (S_ISBLK(st.st_mode))
            throwError(ErrorKind::Io, path,
                       "cannot write: is a block device (uvr does not write onto disks)");
        if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode)) {
            t.kind = OutputKind::Stream;
            return t;
        }
        if (!S_ISREG(st.st_mode))
            throwError(ErrorKind::Io, path, "cannot write: not a regular file");
        t.mode = st.st_mode & 07777;
        t.uid = st.st_uid;
        t.gid = st.st_gid;
    } else {
        const mode_t mask = ::umask(0);
        ::umask(mask);
        t.mode = 0666 & ~mask;
    }
    // Step 4: the temporary goes into the target's folder.
    const std::string folder = folderOf(p);
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        throwError(ErrorKind::Io, path, "cannot write: folder '" + folder + "' does not exist");
    if (::access(folder.c_str(), W_OK | X_OK) != 0)
        throwError(ErrorKind::Io, path, "cannot write: folder '" + folder + "' is not writable");
    return t;
}

OutputFile::OutputFile(const std::string& path) : target_(resolveOutput(path)) {
    if (target_.kind == OutputKind::Stream) {
        if (target_.target == "-") {
            fd_ = STDOUT_FILENO;
            ownsFd_ = false;
        } else {
            struct stat st;
            if (::stat(target_.target.c_str(), &st) == 0 && S_ISSOCK(st.st_mode)) {
                fd_ = connectSocket(target_.target, path);
            } else {
                // A FIFO blocks here until a reader opens it, as a pipeline expects.
                fd_ = ::open(target_.target.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
                if (fd_ < 0) ioError(path, "cannot write", errno);
                if (::isatty(fd_)) {
                    ::close(fd_);
                    fd_ = -1;
                    throwError(ErrorKind::Argument, path,
                               "is a terminal: uvr writes binary files, name a file instead");
                }
            }
        }
    } else {
        // mkostemp: a unique name, created with O_EXCL (a planted link or file is never
        // followed), short (a 255-byte target name still fits), in the target's folder (so the
        // rename is atomic).
        std::string name = folderOf(target_.target) + "/.uvr-XXXXXX";
        fd_ = ::mkostemp(name.data(), O_CLOEXEC);
        if (fd_ < 0) ioError(path, "cannot create a temporary file in its folder", errno);
        tmp_ = name;
        slot_ = registerPending(tmp_);
    }
    buffer_.resize(kBufferBytes);
}

OutputFile::~OutputFile() {
    if (!committed_) release();
}

void OutputFile::release() noexcept {
    if (fd_ >= 0 && ownsFd_) ::close(fd_);
    fd_ = -1;
    if (!tmp_.empty()) ::unlink(tmp_.c_str());
    tmp_.clear();
    unregisterPending(slot_);
    slot_ = -1;
}

void OutputFile::writeAll(const char* data, std::size_t bytes) {
    while (bytes > 0) {
        const ssize_t n = ::write(fd_, data, std::min<std::size_t>(bytes, 1 << 30));
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            throwError(ErrorKind::Io, target_.path,
                       "cannot write (after " + std::to_string(written_) +
                           " bytes): " + std::strerror(err));
        }
        if (n == 0)
            throwError(ErrorKind::Io, target_.path,
                       "cannot write (after " + std::to_string(written_) +
                           " bytes): the system accepted no bytes");
        data += n;
        bytes -= static_cast<std::size_t>(n);
        written_ += static_cast<std::uint64_t>(n);
    }
}

void OutputFile::flush() {
    const std::size_t n = buffered_;
    buffered_ = 0;
    writeAll(buffer_.data(), n);
}

void OutputFile::write(const void* data, std::size_t bytes) {
    if (finished_ || fd_ < 0)
        throwError(ErrorKind::Internal, target_.path, "write after the output was closed");
    if (bytes == 0) return;  // an empty array's data() may be null
    const char* p = static_cast<const char*>(data);
    if (buffered_ + bytes > buffer_.size()) {
        flush();
        if (bytes >= buffer_.size()) {
            writeAll(p, bytes);
            return;
        }
    }
    std::memcpy(buffer_.data() + buffered_, p, bytes);
    buffered_ += bytes;
}

void OutputFile::finish() {
    if (finished_) return;
    flush();
    if (target_.kind == OutputKind::Atomic) {
        // The replaced file's permissions (and owner, where permitted), or the umask's.
        ::fchmod(fd_, static_cast<mode_t>(target_.mode & (denyOthersWrite_ ? ~022u : ~0u)));
        if (target_.exists) {
            struct stat st;
            if (::fstat(fd_, &st) == 0 && (st.st_uid != target_.uid || st.st_gid != target_.gid))
                if (::fchown(fd_, target_.uid, target_.gid) != 0) {
                    // Not permitted for an ordinary user: the file is theirs now, as with cp.
                }
        }
    }
    if (ownsFd_) {
        const int fd = fd_;
        fd_ = -1;
        if (::close(fd) != 0) ioError(target_.path, "cannot write", errno);
    }
    fd_ = -1;
    finished_ = true;
}

void OutputFile::commit() {
    if (committed_) return;
    finish();
    if (target_.kind == OutputKind::Atomic) {
        if (::rename(tmp_.c_str(), target_.target.c_str()) != 0)
            ioError(target_.path, "cannot write", errno);
        tmp_.clear();
        unregisterPending(slot_);
        slot_ = -1;
    }
    committed_ = true;
}

void writeOutput(const std::string& path, const std::function<void(OutputFile&)>& write) {
    OutputFile out(path);
    write(out);
    out.commit();
}

void writeTextOutput(const std::string& path, std::string_view text) {
    OutputFile out(path);
    out.write(text);
    out.commit();
}

void checkOutputsDistinct(const std::vector<NamedFile>& inputs,
                          const std::vector<NamedFile>& outputs) {
    // An output's identity: the inode of an existing file, else the canonical path of the new
    // file its link chain ends at.
    struct Id {
        bool exists = false, device = false;
        dev_t dev = 0;
        ino_t ino = 0;
        std::string path;
    };
    auto idOf = [](const std::string& path) {
        Id id;
        mode_t mode = 0;
        if (path == "-") {
            id.path = "-";
            return id;
        }
        if (fileIdentity(path, id.dev, id.ino, &mode)) {
            id.exists = true;
            id.device = S_ISCHR(mode);
            return id;
        }
        std::error_code ec;
        std::string target = path;
        try {
            target = resolveOutput(path).target;
        } catch (const Error&) {
            // Unwritable outputs are reported when they are opened.
        }
        id.path = fs::weakly_canonical(fs::absolute(target, ec), ec).string();
        return id;
    };
    auto same = [](const Id& a, const Id& b) {
        if (a.exists != b.exists) return false;
        return a.exists ? a.dev == b.dev && a.ino == b.ino : a.path == b.path;
    };
    std::vector<Id> outIds;
    for (const NamedFile& o : outputs) outIds.push_back(idOf(o.path));
    for (size_t i = 0; i < outputs.size(); ++i) {
        if (!outIds[i].exists && outIds[i].path.empty()) continue;
        for (const NamedFile& in : inputs) {
            Id inId;
            if (outIds[i].exists && fileIdentity(in.path, inId.dev, inId.ino)) {
                inId.exists = true;
                if (same(outIds[i], inId))
                    throwError(ErrorKind::Argument, outputs[i].path,
                               outputs[i].role + " names " + in.role + " '" + in.path +
                                   "': refusing to overwrite an input");
            }
        }
        for (size_t k = 0; k < i; ++k)
            if (!outIds[i].device && same(outIds[i], outIds[k]))
                throwError(ErrorKind::Argument, outputs[i].path,
                           outputs[i].role + " names the same file as " + outputs[k].role + " '" +
                               outputs[k].path + "'");
    }
}

void removePendingOutputs() noexcept {
    for (PendingSlot& slot : gPending)
        if (slot.state.load() == 2) ::unlink(slot.path);
}

void installOutputSignalHandlers() {
    struct sigaction sa {};
    sa.sa_handler = onTerminatingSignal;
    sigemptyset(&sa.sa_mask);
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) ::sigaction(sig, &sa, nullptr);
    ::signal(SIGPIPE, SIG_IGN);
    ::signal(SIGXFSZ, SIG_IGN);
}

}  // namespace uvr
