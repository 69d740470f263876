// SPDX-License-Identifier: MIT
#include "uvr/mesh/io/isolated_probe.h"

#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <mutex>
#include <new>

#include "uvr/core/error.h"

// AddressSanitizer's runtime has its own allocator. Up to LLVM 16 it took none of its locks
// around fork, so a child forked while another thread held an allocator lock hung at its first
// allocation (clang 14's, seen in the probe child). Its internal lock functions are declared
// weak here and taken around the probe's fork, as later runtimes do themselves; without them
// (another runtime, or none) nothing is called.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UVR_PROBE_ASAN_FORK_LOCKS 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__)
#define UVR_PROBE_ASAN_FORK_LOCKS 1
#endif
#ifdef UVR_PROBE_ASAN_FORK_LOCKS
namespace __lsan {
__attribute__((weak)) void LockThreadRegistry();
__attribute__((weak)) void UnlockThreadRegistry();
__attribute__((weak)) void LockAllocator();
__attribute__((weak)) void UnlockAllocator();
}  // namespace __lsan
namespace __sanitizer {
__attribute__((weak)) void StackDepotLockAll();
__attribute__((weak)) void StackDepotUnlockAll();
}  // namespace __sanitizer
#endif

namespace uvr {

namespace {

/// True on a thread while it forks a probe child: the fork handlers below act only then, so
/// other forks of the process (Python's subprocesses) are left as they were.
thread_local bool forkingProbe = false;

#ifdef UVR_PROBE_ASAN_FORK_LOCKS
void lockSanitizerAllocator() {
    if (!forkingProbe) return;
    __lsan::LockThreadRegistry();
    __lsan::LockAllocator();
    __sanitizer::StackDepotLockAll();
}

void unlockSanitizerAllocator() {
    if (!forkingProbe) return;
    __sanitizer::StackDepotUnlockAll();
    __lsan::UnlockAllocator();
    __lsan::UnlockThreadRegistry();
}

/// Fork handlers, registered at start-up: before libomp's (registered at its first parallel
/// region), so the locks are held only around the fork itself. libomp's child handler
/// allocates, and would wait forever on a lock held across it.
[[maybe_unused]] const bool sanitizerForkHandlers =
    __lsan::LockThreadRegistry && __lsan::UnlockThreadRegistry && __lsan::LockAllocator &&
    __lsan::UnlockAllocator && __sanitizer::StackDepotLockAll && __sanitizer::StackDepotUnlockAll &&
    pthread_atfork(lockSanitizerAllocator, unlockSanitizerAllocator, unlockSanitizerAllocator) == 0;
#endif

std::mutex& limitsMutex() {
    static std::mutex mutex;
    return mutex;
}

ProbeLimits& currentLimits() {
    static ProbeLimits limits;
    return limits;
}

std::recursive_mutex& libraryMutex() {
    static std::recursive_mutex mutex;
    return mutex;
}

/// True in a probe child (set after fork, before the probe runs; the child has one thread).
bool inProbeChild = false;

/// The answer a child writes to its pipe: one tag byte, then the message.
constexpr char kAnswerOk = 'K', kAnswerError = 'E', kAnswerMemory = 'M', kAnswerOther = 'X';

/// Bytes of address space the process maps now (/proc/self/statm's first field), 0 if unknown.
std::uint64_t mappedBytes() {
    std::ifstream statm("/proc/self/statm");
    std::uint64_t pages = 0;
    if (!(statm >> pages)) return 0;
    return pages * static_cast<std::uint64_t>(sysconf(_SC_PAGESIZE));
}

/// Writes all of text to fd (the child's answer; errors ignored: the parent sees no answer).
void writeAll(int fd, const std::string& text) {
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = write(fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        done += static_cast<std::size_t>(n);
    }
}

/// The child's side: limits, the probe, its answer, _exit (no destructors, atexit handlers or
/// stdio flushes of the parent's state).
[[noreturn]] void runChild(int answerFd, const ProbeLimits& limits,
                           const std::function<void()>& probe) {
    inProbeChild = true;
    // No core dump of a crash the parent reports; no output into the parent's terminal.
    const rlimit noCore{0, 0};
    setrlimit(RLIMIT_CORE, &noCore);
    const rlim_t cpu = static_cast<rlim_t>(std::ceil(limits.seconds)) + 1;
    const rlimit cpuLimit{cpu, cpu + 1};
    setrlimit(RLIMIT_CPU, &cpuLimit);
    if (const std::uint64_t mapped = mappedBytes(); mapped > 0) {
        rlimit as{};
        getrlimit(RLIMIT_AS, &as);
        const rlim_t want = static_cast<rlim_t>(mapped + limits.memoryBytes);
        if (as.rlim_cur == RLIM_INFINITY || as.rlim_cur > want) {
            as.rlim_cur = want;
            setrlimit(RLIMIT_AS, &as);
        }
    }
    // The host's crash handlers (Python's faulthandler, a sanitizer's) are not the child's: a
    // crash ends it at once, by the signal the parent reports.
    for (const int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGXCPU})
        signal(sig, SIG_DFL);
    if (const int null = open("/dev/null", O_WRONLY | O_CLOEXEC); null >= 0) {
        dup2(null, STDOUT_FILENO);
        dup2(null, STDERR_FILENO);
    }
    std::string answer(1, kAnswerOk);
    try {
        probe();
    } catch (const Error& e) {
        answer = std::string(1, kAnswerError) + static_cast<char>('0' + int(e.kind())) + e.what();
    } catch (const std::bad_alloc&) {
        answer = std::string(1, kAnswerMemory);
    } catch (const std::exception& e) {
        answer = std::string(1, kAnswerOther) + e.what();
    } catch (...) {
        answer = std::string(1, kAnswerOther);
    }
    writeAll(answerFd, answer);
    _exit(0);
}

/// Reads the child's answer until end of file or the deadline; false when the deadline passed.
bool readAnswer(int fd, std::chrono::steady_clock::time_point deadline, std::string& answer) {
    char buffer[4096];
    for (;;) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) return false;
        pollfd p{fd, POLLIN, 0};
        const int ready = poll(&p, 1, static_cast<int>(std::min<long long>(left.count(), 1 << 30)));
        if (ready < 0 && errno == EINTR) continue;
        if (ready < 0) return true;  // treated as no answer
        if (ready == 0) continue;    // the loop re-checks the deadline
        const ssize_t n = read(fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return true;  // end of file: the child is gone
        answer.append(buffer, static_cast<std::size_t>(n));
    }
}

std::string secondsText(double s) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", s);
    return text;
}

}  // namespace

ProbeLimits probeLimits() {
    const std::lock_guard<std::mutex> lock(limitsMutex());
    return currentLimits();
}

void setProbeLimits(const ProbeLimits& limits) {
    const std::lock_guard<std::mutex> lock(limitsMutex());
    currentLimits() = limits;
}

FormatLibraryLock::FormatLibraryLock() {
    if (inProbeChild) return;
    libraryMutex().lock();
    locked_ = true;
}

FormatLibraryLock::~FormatLibraryLock() {
    if (locked_) libraryMutex().unlock();
}

void runIsolatedProbe(const std::string& file, const std::string& library,
                      const std::function<void()>& probe) {
    const ProbeLimits limits = probeLimits();
    if (!limits.isolate || inProbeChild) {
        probe();
        return;
    }
    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0)
        throwError(ErrorKind::Io, file,
                   "cannot make a pipe to check the file in a child process: " +
                       std::string(std::strerror(errno)));
    forkingProbe = true;
    const pid_t pid = fork();
    forkingProbe = false;
    if (pid < 0) {
        const int err = errno;
        close(fds[0]);
        close(fds[1]);
        throwError(
            ErrorKind::Io, file,
            "cannot start a child process to check the file: " + std::string(std::strerror(err)));
    }
    if (pid == 0) {
        close(fds[0]);
        runChild(fds[1], limits, probe);
    }
    close(fds[1]);
    std::string answer;
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(limits.seconds));
    const bool answered = readAnswer(fds[0], deadline, answer);
    close(fds[0]);
    if (!answered) kill(pid, SIGKILL);
    int status = 0;
    pid_t waited = -1;
    do {
        waited = waitpid(pid, &status, 0);
    } while (waited < 0 && errno == EINTR);
    // (waited < 0: SIGCHLD is ignored by the host and the child was reaped; the answer decides.)

    const std::string failed = "the " + library + " library failed on this file (";
    if (!answered)
        throwError(
            ErrorKind::Parse, file,
            failed + "no answer in " + secondsText(limits.seconds) + " s): the file is malformed");
    if (!answer.empty() && answer[0] == kAnswerOk) return;
    if (answer.size() >= 2 && answer[0] == kAnswerError) {
        const int kind = answer[1] - '0';
        if (kind >= 0 && kind <= int(ErrorKind::Internal))
            throw Error(static_cast<ErrorKind>(kind), answer.substr(2));
    }
    if (!answer.empty() && answer[0] == kAnswerMemory)
        throwError(ErrorKind::Resource, file,
                   "the " + library + " library needed more than " +
                       std::to_string(limits.memoryBytes >> 20) +
                       " MiB to read the file's structure: the file is malformed or absurd");
    if (!answer.empty() && answer[0] == kAnswerOther)
        throwError(ErrorKind::Parse, file,
                   "the " + library + " library failed on this file: " + answer.substr(1));
    if (waited == pid && WIFSIGNALED(status)) {
        const int sig = WTERMSIG(status);
        const char* what = sig == SIGXCPU ? "its CPU-time limit" : strsignal(sig);
        throwError(ErrorKind::Parse, file,
                   failed + "signal " + std::to_string(sig) + ", " + (what ? what : "?") +
                       "): the file is malformed");
    }
    throwError(ErrorKind::Parse, file,
               failed + "it ended without an answer" +
                   (waited == pid && WIFEXITED(status)
                        ? ", exit status " + std::to_string(WEXITSTATUS(status))
                        : std::string()) +
                   "): the file is malformed");
}

FileIdentity fileIdentity(const std::string& path) {
    struct stat st {};
    if (stat(path.c_str(), &st) != 0)
        throwError(ErrorKind::Io, path, "cannot read: " + std::string(std::strerror(errno)));
    FileIdentity id;
    id.device = static_cast<std::uint64_t>(st.st_dev);
    id.inode = static_cast<std::uint64_t>(st.st_ino);
    id.size = static_cast<std::uint64_t>(st.st_size);
    id.mtimeNs = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
    return id;
}

void expectSameFile(const std::string& path, const FileIdentity& identity) {
    if (!(fileIdentity(path) == identity))
        throwError(ErrorKind::Io, path,
                   "the file changed while it was read (checked, then replaced or written)");
}

}  // namespace uvr
