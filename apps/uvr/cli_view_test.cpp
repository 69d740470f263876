// SPDX-License-Identifier: MIT
// `uvr view`'s own flags fail before the mesh is read (the server itself: src/uvr/server).
#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>

#include "cli_test_support.h"
#include "test_support.h"

namespace uvr {
namespace {

using cli_testing::CliRun;
using cli_testing::expectOneLineError;
using cli_testing::uvr;
using ::testing::HasSubstr;
using ::testing::Not;

TEST(CliView, BadServerFlagsAndABusyPortFailBeforeTheMeshIsRead) {
    const std::string dir = testing::scratchDir();
    const std::string m = dir + "/m.uvrm";
    ASSERT_EQ(uvr("-q generate box --cells 3000 --fields jet -o " + m, dir).code, 0);
    // Without -q a read prints "uvr: read ...": a one-line error means nothing was read. A
    // server that starts anyway is stopped by `timeout` (exit 124), and the case fails.
    auto view = [&](const std::string& args) {
        return uvr("view " + m + " " + args, dir, "timeout 60 ");
    };
    expectOneLineError(view("--token short"), {"--token"}, "--token");
    expectOneLineError(view("--token '0123456789abcdef;x'"), {"--token"}, "--token ;");
    expectOneLineError(view("--host not-an-address"), {"--host not-an-address"}, "--host");
    expectOneLineError(view("--port 70000"), {"--port"}, "--port");
    expectOneLineError(view("--moving-frame-ms 0"), {"--moving-frame-ms"}, "--moving-frame-ms");
    expectOneLineError(view("--tf nosuch"), {"nosuch"}, "--tf");
    // Issue 28: the page's own limit on a side (4096), not render's 16384.
    expectOneLineError(view("--size 8192x8192"), {"--size '8192x8192'", "from 16 to 4096"},
                       "--size over the page's limit");
    expectOneLineError(view("--size 4097x100"), {"--size", "4096"}, "--size 4097");
    expectOneLineError(view("--size 8x8"), {"--size", "from 16"}, "--size under");
    // A port another program listens on.
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0;
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    ASSERT_EQ(::listen(fd, 1), 0);
    socklen_t len = sizeof addr;
    ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len), 0);
    const std::string port = std::to_string(ntohs(addr.sin_port));
    expectOneLineError(view("--port " + port), {"cannot listen on 127.0.0.1:" + port}, "busy port");
    ::close(fd);
}

TEST(CliView, APreparedCacheIsServedWithoutReadingTheMesh) {
    // Issue 35: `uvr view` takes MESH.uvrprep as `uvr render` does. `timeout` stops each server
    // once it serves (a server's SIGTERM ends it cleanly).
    const std::string dir = testing::scratchDir();
    const std::string m = dir + "/m.uvrm";
    ASSERT_EQ(uvr("-q generate box --cells 3000 --fields jet,linear -o " + m, dir).code, 0);
    ASSERT_EQ(uvr("-q prepare " + m + " --field linear", dir).code, 0);
    const auto view = [&](const std::string& args) {
        return uvr("view " + m + " --port 0 " + args, dir, "timeout 5 ");
    };
    CliRun r = view("--field linear");
    EXPECT_THAT(r.err, HasSubstr("using the prepared cache " + m + ".uvrprep"));
    EXPECT_THAT(r.err, HasSubstr("serving the prepared cache's linear (point data) alone "
                                 "(methods: auto, "));
    EXPECT_THAT(r.out, HasSubstr("uvr: serving http://127.0.0.1:"));
    EXPECT_THAT(r.err, Not(HasSubstr("uvr: read ")));
    // Another field than the cache's: the mesh is read, saying why.
    r = view("");
    EXPECT_THAT(r.err, HasSubstr("not using the prepared cache"));
    EXPECT_THAT(r.err, HasSubstr("uvr: read "));
    EXPECT_THAT(r.out, HasSubstr("uvr: serving http://127.0.0.1:"));
    // --no-cache reads the mesh, silently; --cache naming no file is an error before reading.
    r = view("--field linear --no-cache");
    EXPECT_THAT(r.err, Not(HasSubstr("prepared cache")));
    EXPECT_THAT(r.err, HasSubstr("uvr: read "));
    expectOneLineError(view("--cache " + dir + "/none.uvrprep"), {"none.uvrprep"}, "--cache");
}

}  // namespace
}  // namespace uvr
