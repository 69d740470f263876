// SPDX-License-Identifier: MIT
#pragma once

#include <gtest/gtest.h>

#include "uvr/core/error.h"
#include "uvr/core/vec.h"
#include "uvr/tf/tf_table.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace uvr::testing {

/// Opacity of a path `length` long through a medium of constant transfer-function opacity alpha
/// per opacity unit `unit` under a law, in double: 1 - exp(-alpha L / u) (attenuation), 1 - (1 -
/// alpha)^(L / u) (transmittance). The closed form the integrators are held to.
inline double slabOpacity(double alpha, double length, double unit,
                          OpacityLaw law = kDefaultOpacityLaw) {
    length = length > 0.0 ? length : 0.0;
    if (law == OpacityLaw::Attenuation) return -std::expm1(-alpha * length / unit);
    return alpha >= 1.0 ? (length > 0.0 ? 1.0 : 0.0) : 1.0 - std::pow(1.0 - alpha, length / unit);
}

/// Path of a real mesh in ../shared/data; the test is skipped when the folder is absent.
/// The folder is UVR_SHARED_DATA_DIR, or the environment variable UVR_SHARED_DATA when set (for
/// running a carried test binary on another machine).
inline std::string sharedData(const std::string& name) {
    const char* env = std::getenv("UVR_SHARED_DATA");
    return std::string(env ? env : UVR_SHARED_DATA_DIR) + "/" + name;
}

/// ParaView's tutorial data disk_out_ref.ex2 (7,472 hexahedra, Exodus II), as Debian's mayavi2
/// package ships it (scripts/install-deps.sh --tests installs it; tests skip it when absent).
inline constexpr const char* kDiskOutRef =
    "/usr/lib/python3/dist-packages/mayavi/tests/data/disk_out_ref.ex2";

/// True when the shared data folder is present (tests that need it GTEST_SKIP otherwise).
inline bool haveSharedData() {
    return std::filesystem::exists(sharedData("spx.vtk"));
}

/// Path of a helper script in tests/tools.
inline std::string testTool(const std::string& name) {
    return UVR_TEST_TOOLS_DIR "/" + name;  // not std::string(dir) + "/": GCC 12's -Warray-bounds
}

/// Path of a data file in tests/data (the repository's own small inputs).
inline std::string testData(const std::string& name) {
    return UVR_TEST_TOOLS_DIR "/../data/" + name;
}

/// A fresh, empty folder for this test's files under the system temp folder.
inline std::string scratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::filesystem::path dir = std::filesystem::temp_directory_path() / "uvr_tests" /
                                (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

/// True when two arrays (any vector type) hold the same bytes.
template <class T>
bool sameBytes(const T& a, const T& b) {
    return a.size() == b.size() &&
           (a.empty() ||
            std::memcmp(a.data(), b.data(), a.size() * sizeof(typename T::value_type)) == 0);
}

/// The whole file's bytes ("" when it cannot be read).
inline std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes;
    char buf[1 << 16];
    while (in.read(buf, sizeof buf) || in.gcount() > 0) bytes.append(buf, std::size_t(in.gcount()));
    return bytes;
}

/// Writes text (or bytes) to a file and returns its path.
inline std::string writeFile(const std::string& path, const std::string& contents) {
    std::ofstream out(path, std::ios::binary);
    out << contents;
    return path;
}

/// Debian's system Python (with python3-vtk9, python3-meshio, python3-skimage), not a pyenv one.
inline const char* systemPython() {
    return "/usr/bin/python3";
}

/// True when the system Python can import the module.
inline bool pythonHas(const std::string& module) {
    std::string cmd = std::string(systemPython()) + " -c 'import " + module + "' >/dev/null 2>&1";
    return std::system(cmd.c_str()) == 0;
}

/// True when this build runs under AddressSanitizer (whose shadow memory needs far more address
/// space than an address-space limit such as `ulimit -v` leaves): gcc defines
/// __SANITIZE_ADDRESS__, clang answers __has_feature.
constexpr bool underAddressSanitizer() {
#if defined(__SANITIZE_ADDRESS__)
    return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    return true;
#else
    return false;
#endif
#else
    return false;
#endif
}

/// Path of the uvr command-line binary built beside the tests.
inline std::string uvrBinary() {
    const char* env = std::getenv("UVR_BIN");  // a carried binary on another machine
    return env ? env : UVR_BIN_PATH;
}

/// Runs a shell command, returning its exit status (the shell's, 0..255).
inline int runCommand(const std::string& cmd) {
    int status = std::system(cmd.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : 255;
}

/// Runs f and returns the uvr::Error it throws (the test fails when it throws none).
template <typename F>
Error catchError(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e;
    }
    ADD_FAILURE() << "expected a uvr::Error";
    return Error(ErrorKind::Internal, "no error");
}

/// Runs f, expecting a uvr::Error of `kind` whose one-line message holds every part.
template <typename F>
void expectError(F&& f, ErrorKind kind, const std::vector<std::string>& parts) {
    try {
        f();
        ADD_FAILURE() << "no error thrown";
    } catch (const Error& e) {
        EXPECT_EQ(static_cast<int>(e.kind()), static_cast<int>(kind)) << e.what();
        for (const std::string& p : parts)
            EXPECT_NE(std::string(e.what()).find(p), std::string::npos)
                << "no '" << p << "' in: " << e.what();
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
    }
}

/// Lines of a text (its newlines).
inline int lineCount(const std::string& s) {
    return static_cast<int>(std::count(s.begin(), s.end(), '\n'));
}

/// Runs a Python script with the system Python in dir and returns its stdout parsed as numbers.
inline std::vector<double> runPython(const std::string& dir, const std::string& script) {
    const std::string py = writeFile(dir + "/oracle.py", script);
    const std::string out = dir + "/oracle.txt";
    EXPECT_EQ(runCommand(std::string(systemPython()) + " " + py + " > " + out + " 2>/dev/null"), 0);
    std::ifstream in(out);
    std::vector<double> values;
    double v;
    while (in >> v) values.push_back(v);
    return values;
}

/// Expects two vectors to agree component-wise within tol.
inline void expectVec(Vec3f got, Vec3f want, float tol, const std::string& what = "") {
    EXPECT_NEAR(got.x, want.x, tol) << what;
    EXPECT_NEAR(got.y, want.y, tol) << what;
    EXPECT_NEAR(got.z, want.z, tol) << what;
}

}  // namespace uvr::testing
