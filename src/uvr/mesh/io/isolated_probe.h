// SPDX-License-Identifier: MIT
// Isolation of the third-party file libraries (libnetcdf, libhdf5) from untrusted files: they
// crash (SIGSEGV, double free) and loop forever on some malformed files, and uvr cannot fix
// them. A reader first walks a file's whole structure in a forked child process with resource
// limits; only when the child answers that the walk succeeded does the reader open the file for
// real in the calling process. A child killed by a signal, or silent past the time limit,
// becomes an Error(Parse) naming the file and the library.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

namespace uvr {

/// The limits a probe child runs under.
struct ProbeLimits {
    /// Wall-clock seconds before the parent kills the child (also its CPU-time limit).
    double seconds = 20;
    /// Address space the child may map beyond what it inherits (RLIMIT_AS).
    std::uint64_t memoryBytes = std::uint64_t{2} << 30;
    /// False runs the probe in the calling process (fuzzers that must see the libraries' own
    /// crashes, and only they).
    bool isolate = true;
};

/// The limits probes run under now (the defaults above unless setProbeLimits changed them).
ProbeLimits probeLimits();
/// Replaces the limits of every later probe (tests shorten the time; fuzzers may run in-process).
void setProbeLimits(const ProbeLimits& limits);

/// Sets the probes' time limit for its own lifetime and then restores the limits it found (tests
/// shorten the wait for a hanging library this way).
class ScopedProbeSeconds {
public:
    explicit ScopedProbeSeconds(double seconds) : saved_(probeLimits()) {
        ProbeLimits limits = saved_;
        limits.seconds = seconds;
        setProbeLimits(limits);
    }
    ~ScopedProbeSeconds() { setProbeLimits(saved_); }
    ScopedProbeSeconds(const ScopedProbeSeconds&) = delete;
    ScopedProbeSeconds& operator=(const ScopedProbeSeconds&) = delete;

private:
    ProbeLimits saved_;
};

/// Runs probe (which calls the library `library` on `file`) in a forked child under
/// probeLimits(), and returns when it succeeded. A uvr::Error thrown by probe is thrown again
/// here (same kind and message); another exception becomes Error(Resource) (the child's memory
/// limit); a child killed by a signal, ending without an answer or silent past the time limit
/// becomes Error(Parse) "FILE: the LIBRARY library failed on this file (signal 11, ...): the
/// file is malformed". The caller must hold formatLibraryLock (no other thread is inside the
/// library when the process forks); the child calls only probe and then _exit()s, so forking a
/// multi-threaded process (the viewer's server, Python) is safe. Error(Io) when fork fails.
void runIsolatedProbe(const std::string& file, const std::string& library,
                      const std::function<void()>& probe);

/// Serialises every call into libnetcdf and libhdf5 (neither is built thread-safe), and so
/// makes sure no other thread is inside them when a probe forks. Recursive; a no-op in a probe
/// child, whose only thread runs the probe.
class FormatLibraryLock {
public:
    FormatLibraryLock();
    ~FormatLibraryLock();
    FormatLibraryLock(const FormatLibraryLock&) = delete;
    FormatLibraryLock& operator=(const FormatLibraryLock&) = delete;

private:
    bool locked_ = false;
};

/// The identity of a file (device, inode, size, modification time), to check that the file a
/// probe walked is the one then read.
struct FileIdentity {
    std::uint64_t device = 0, inode = 0, size = 0;
    std::int64_t mtimeNs = 0;
    bool operator==(const FileIdentity&) const = default;
};

/// The identity of path now; Error(Io) when it cannot be read.
FileIdentity fileIdentity(const std::string& path);

/// Error(Io) "FILE: the file changed while it was read" unless path still has identity.
void expectSameFile(const std::string& path, const FileIdentity& identity);

}  // namespace uvr
