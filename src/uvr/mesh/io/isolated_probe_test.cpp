// SPDX-License-Identifier: MIT
// The probe child: a crash, a hang, an error and an allocation beyond its limit each become a
// uvr::Error naming the file, and the calling process goes on (also with other threads).
#include "uvr/mesh/io/isolated_probe.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

using testing::catchError;

TEST(IsolatedProbe, SuccessReturns) {
    const FormatLibraryLock lock;
    runIsolatedProbe("f.e", "netCDF", [] {});
}

TEST(IsolatedProbe, ACrashIsAParseErrorNamingFileAndLibrary) {
    const FormatLibraryLock lock;
    const Error e = catchError([] { runIsolatedProbe("bad.e", "netCDF", [] { raise(SIGSEGV); }); });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_EQ(
        std::string(e.what()).rfind("bad.e: the netCDF library failed on this file (signal 11", 0),
        0u)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("the file is malformed"), std::string::npos);
    const Error abort =
        catchError([] { runIsolatedProbe("bad.vtkhdf", "HDF5", [] { std::abort(); }); });
    EXPECT_NE(std::string(abort.what()).find("signal 6"), std::string::npos) << abort.what();
}

TEST(IsolatedProbe, AHangIsKilledAfterTheTimeLimit) {
    const ScopedProbeSeconds shortProbes(0.5);
    const FormatLibraryLock lock;
    const Error e = catchError([] {
        runIsolatedProbe("loop.e", "HDF5", [] {
            for (;;) pause();
        });
    });
    EXPECT_EQ(e.kind(), ErrorKind::Parse);
    EXPECT_NE(std::string(e.what()).find("loop.e: the HDF5 library failed on this file (no answer "
                                         "in 0.5 s): the file is malformed"),
              std::string::npos)
        << e.what();
}

TEST(IsolatedProbe, TheProbesErrorComesBackAsItWas) {
    const FormatLibraryLock lock;
    const Error e = catchError([] {
        runIsolatedProbe("x.e", "netCDF",
                         [] { throwError(ErrorKind::Unsupported, "x.e", "an external link"); });
    });
    EXPECT_EQ(e.kind(), ErrorKind::Unsupported);
    EXPECT_STREQ(e.what(), "x.e: an external link");
}

TEST(IsolatedProbe, AllocationsBeyondTheMemoryLimitFail) {
    ProbeLimits saved = probeLimits(), small = saved;
    small.memoryBytes = 64u << 20;
    setProbeLimits(small);
    const FormatLibraryLock lock;
    const Error e = catchError([] {
        runIsolatedProbe("big.e", "netCDF", [] {
            std::vector<char> huge(std::size_t{1} << 32, 1);
            if (huge[12345] != 1) std::abort();
        });
    });
    setProbeLimits(saved);
    // (A sanitizer's allocator may abort instead of throwing bad_alloc: a signal, also Parse.)
    EXPECT_TRUE(e.kind() == ErrorKind::Resource || e.kind() == ErrorKind::Parse) << e.what();
    EXPECT_NE(std::string(e.what()).find("big.e: the netCDF library"), std::string::npos)
        << e.what();
}

TEST(IsolatedProbe, ForksSafelyWhileOtherThreadsRun) {
    // Threads that allocate and take the library lock while probes fork: every probe answers.
    std::atomic<bool> stop{false};
    std::vector<std::thread> busy;
    for (int t = 0; t < 3; ++t)
        busy.emplace_back([&] {
            while (!stop) {
                const FormatLibraryLock lock;
                std::vector<int> v(1000, 1);
                (void)v;
            }
        });
    for (int k = 0; k < 20; ++k) {
        const FormatLibraryLock lock;
        runIsolatedProbe("f.e", "netCDF", [] {
            const FormatLibraryLock inner;  // no deadlock on the lock held at the fork
            std::vector<int> v(1 << 16, 2);
            if (v[7] != 2) std::abort();
        });
    }
    stop = true;
    for (std::thread& t : busy) t.join();
}

TEST(IsolatedProbe, ForksSafelyWhileOtherThreadsAllocate) {
    // Threads that allocate outside the library lock (the view server's ranks, Python's threads)
    // while probes fork: an allocator lock one of them held at the fork must not hang the child.
    // (clang 14's AddressSanitizer takes none of its allocator's locks around fork: in its
    // build a child hung within the first 16 probes on each of 5 runs, until
    // isolated_probe.cpp took them itself.)
    std::atomic<bool> stop{false};
    std::vector<std::thread> busy;
    for (int t = 0; t < 3; ++t)
        busy.emplace_back([&, t] {
            std::size_t size = 16 + 8 * t;
            while (!stop) {
                std::vector<char> v(size, 1);
                (void)v;
                size = size < (1u << 20) ? size * 2 : 16 + 8 * t;
            }
        });
    int answered = 0;
    std::string failure;
    try {
        for (; answered < 200; ++answered) {
            const FormatLibraryLock lock;
            runIsolatedProbe("f.e", "netCDF", [] {
                for (std::size_t size = 16; size <= (1u << 20); size *= 2) {
                    std::vector<char> v(size, 2);
                    if (v[size - 1] != 2) std::abort();
                }
            });
        }
    } catch (const Error& e) {
        failure = e.what();
    }
    stop = true;
    for (std::thread& t : busy) t.join();
    EXPECT_EQ(answered, 200) << failure;
}

TEST(IsolatedProbe, TheFileIdentityNoticesAReplacement) {
    const std::string dir = testing::scratchDir();
    const std::string a = testing::writeFile(dir + "/a.e", "one");
    const FileIdentity before = fileIdentity(a);
    expectSameFile(a, before);
    testing::writeFile(dir + "/b.e", "other");
    std::rename((dir + "/b.e").c_str(), a.c_str());
    EXPECT_EQ(catchError([&] { expectSameFile(a, before); }).kind(), ErrorKind::Io);
}

}  // namespace
}  // namespace uvr
