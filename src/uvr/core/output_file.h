// SPDX-License-Identifier: MIT
// The one way uvr writes an output file: regular files atomically through a safely created
// temporary, symbolic links through to their target, devices/FIFOs/sockets/standard output in
// place, every write checked, temporaries removed on errors and on SIGINT/SIGTERM.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace uvr {

/// How an output is written, decided from what its path names before anything is written.
enum class OutputKind {
    Atomic,  ///< a regular file or a new name: a temporary beside it, renamed over it on commit
    Stream,  ///< a character device, FIFO, socket or standard output ("-"): written in place
};

/// An output path resolved: symbolic links followed to the file they name (which is written,
/// the links kept), and the way it will be written.
struct OutputTarget {
    std::string path;    ///< as given (used in messages)
    std::string target;  ///< what is written: the end of the symbolic-link chain, or "-"
    OutputKind kind = OutputKind::Atomic;
    bool exists = false;        ///< the target exists (a regular file is then replaced)
    unsigned mode = 0666;       ///< permission bits for the written file (the replaced file's own)
    unsigned uid = 0, gid = 0;  ///< owner of the replaced file (restored where permitted)
};

/// Resolves an output path and checks that it can be written: "-" is standard output (refused
/// when it is a terminal); a folder, a block device or a terminal is refused; an atomic output
/// needs an existing, writable folder. In a folder that is sticky and writable by everyone
/// (/tmp), a symbolic link of the chain or the existing file it ends at must belong to the
/// current effective user or to the folder's owner (the kernel's protected_symlinks and
/// protected_regular rules: uvr follows the links itself, so the kernel's cannot apply).
/// Throws Error(Io) or Error(Argument) naming the path.
OutputTarget resolveOutput(const std::string& path);

/// One output being written. Bytes are buffered and every write is checked (a full disk, a
/// closed pipe or a size limit is an Error(Io) naming the path); commit() makes the output
/// appear. Until then a regular file is untouched: the bytes go to a temporary `.uvr-XXXXXX`
/// created with O_EXCL in the target's folder, removed by the destructor when not committed and
/// by the signal handlers of installOutputSignalHandlers().
class OutputFile {
public:
    /// Resolves path and opens the temporary (or the device, FIFO, socket, standard output).
    explicit OutputFile(const std::string& path);
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;
    /// Abandons an uncommitted output: closes it and removes its temporary.
    ~OutputFile();

    /// Appends bytes; throws Error(Io) when the system refuses them.
    void write(const void* data, std::size_t bytes);
    /// Appends text.
    void write(std::string_view text) { write(text.data(), text.size()); }
    /// Bytes appended so far.
    std::uint64_t size() const { return written_ + buffered_; }
    /// Flushes and closes (checked) without making the output appear: after finish() on every
    /// output of a command, the commits that follow only rename.
    void finish();
    /// finish(), then renames the temporary over the target.
    void commit();
    /// The path as given.
    const std::string& path() const { return target_.path; }
    /// The written file will not be writable by its group or others, whatever the umask or the
    /// replaced file's mode (for files whose readers trust only such files: prepared caches).
    void denyOthersWrite() { denyOthersWrite_ = true; }

private:
    void flush();
    void writeAll(const char* data, std::size_t bytes);
    void release() noexcept;

    OutputTarget target_;
    int fd_ = -1;
    bool ownsFd_ = true;
    std::string tmp_;
    int slot_ = -1;
    std::vector<char> buffer_;
    std::size_t buffered_ = 0;
    std::uint64_t written_ = 0;
    bool finished_ = false;
    bool committed_ = false;
    bool denyOthersWrite_ = false;
};

/// Writes an output through write(out) and commits it; on any exception the output is abandoned
/// (nothing is left behind and a replaced file is untouched) and the exception propagates.
void writeOutput(const std::string& path, const std::function<void(OutputFile&)>& write);

/// Writes text as a whole output.
void writeTextOutput(const std::string& path, std::string_view text);

/// A file a command reads or writes, with what names it in messages (a flag or "input mesh").
struct NamedFile {
    std::string role;  ///< e.g. "-o", "--stats", "the input mesh"
    std::string path;
};

/// Throws Error(Argument) when an output names the same file as an input (so that the command
/// would destroy its own input) or as another output. Character devices (/dev/null) may be
/// named more than once; "-" only once.
void checkOutputsDistinct(const std::vector<NamedFile>& inputs,
                          const std::vector<NamedFile>& outputs);

/// Removes every uncommitted temporary of this process; async-signal-safe.
void removePendingOutputs() noexcept;

/// For programs (not for a library's host process): SIGINT, SIGTERM, SIGHUP and SIGQUIT remove
/// the pending temporaries and then end the process by the same signal; SIGPIPE and SIGXFSZ are
/// ignored, so a closed pipe or a file-size limit becomes a write error with a message.
void installOutputSignalHandlers();

}  // namespace uvr
