// SPDX-License-Identifier: MIT
// The output writer against every kind of path an output can name: new and existing files,
// symbolic links, FIFOs, sockets, devices, terminals, folders; full disks, size limits and signals.
#include "uvr/core/output_file.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "test_support.h"
#include "uvr/core/error.h"

namespace uvr {
namespace {

/// Names in a folder, sorted.
std::vector<std::string> listing(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    return names;
}

/// The message of the Error f throws, or "" when it throws none.
template <typename F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

TEST(OutputFile, NewFileAppearsOnlyOnCommitWithTheUmasksMode) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/out.txt";
    const mode_t old = ::umask(027);
    {
        OutputFile out(path);
        out.write("hello ");
        // Before the commit: only a short, hidden temporary in the target's folder.
        const auto names = listing(dir);
        ASSERT_EQ(names.size(), 1u);
        EXPECT_EQ(names[0].rfind(".uvr-", 0), 0u) << names[0];
        EXPECT_EQ(names[0].size(), 11u);
        out.write(std::string(3 << 20, 'x'));  // larger than the buffer
        out.commit();
    }
    ::umask(old);
    EXPECT_EQ(listing(dir), std::vector<std::string>{"out.txt"});
    EXPECT_EQ(testing::readFile(path), "hello " + std::string(3 << 20, 'x'));
    struct stat st;
    ASSERT_EQ(::stat(path.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0640u);
}

TEST(OutputFile, AbandonedOutputLeavesTheOldFileAndNoTemporary) {
    const std::string dir = testing::scratchDir();
    const std::string path = testing::writeFile(dir + "/out.txt", "old");
    ::chmod(path.c_str(), 0604);
    EXPECT_THROW(writeOutput(path,
                             [](OutputFile& out) {
                                 out.write("half");
                                 throw Error(ErrorKind::Io, "simulated failure");
                             }),
                 Error);
    EXPECT_EQ(listing(dir), std::vector<std::string>{"out.txt"});
    EXPECT_EQ(testing::readFile(path), "old");
    writeTextOutput(path, "new");
    EXPECT_EQ(testing::readFile(path), "new");
    struct stat st;
    ASSERT_EQ(::stat(path.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0604u) << "a replaced file keeps its permissions";
}

TEST(OutputFile, SymbolicLinksAreWrittenThroughAndKept) {
    const std::string dir = testing::scratchDir();
    std::filesystem::create_directories(dir + "/runs/42");
    const std::string target = testing::writeFile(dir + "/runs/42/out.png", "old");
    std::filesystem::create_symlink("runs/42/out.png", dir + "/latest.png");  // relative link
    std::filesystem::create_symlink(dir + "/latest.png",
                                    dir + "/chain.png");  // absolute link to a link
    writeTextOutput(dir + "/chain.png", "new");
    EXPECT_TRUE(std::filesystem::is_symlink(dir + "/latest.png"));
    EXPECT_TRUE(std::filesystem::is_symlink(dir + "/chain.png"));
    EXPECT_EQ(testing::readFile(target), "new");
    EXPECT_EQ(listing(dir + "/runs/42"), std::vector<std::string>{"out.png"});
    // A dangling link: the file it names is created.
    std::filesystem::create_symlink("runs/42/next.png", dir + "/next.png");
    writeTextOutput(dir + "/next.png", "created");
    EXPECT_TRUE(std::filesystem::is_symlink(dir + "/next.png"));
    EXPECT_EQ(testing::readFile(dir + "/runs/42/next.png"), "created");
    // A loop is an error, not a hang.
    std::filesystem::create_symlink(dir + "/loop-b", dir + "/loop-a");
    std::filesystem::create_symlink(dir + "/loop-a", dir + "/loop-b");
    EXPECT_TRUE(contains(errorOf([&] { writeTextOutput(dir + "/loop-a", "x"); }),
                         "too many levels of symbolic links"));
}

/// A folder like /tmp: sticky and writable by everyone.
std::string sharedFolder(const std::string& parent) {
    const std::string dir = parent + "/shared";
    std::filesystem::create_directories(dir);
    EXPECT_EQ(::chmod(dir.c_str(), 01777), 0);
    return dir;
}

constexpr uid_t kOtherUser = 65534;  // nobody

TEST(OutputFile, LinksPlantedByAnotherUserInASharedFolderAreNotFollowed) {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a link to another user";
    const std::string dir = testing::scratchDir();
    const std::string shared = sharedFolder(dir);
    const std::string victim = testing::writeFile(dir + "/victim", "precious");
    const std::string link = shared + "/frame_0000.png";
    std::filesystem::create_symlink(victim, link);
    ASSERT_EQ(::lchown(link.c_str(), kOtherUser, kOtherUser), 0);
    const std::string error = errorOf([&] { writeTextOutput(link, "png"); });
    EXPECT_TRUE(contains(error, "refusing to follow the symbolic link '" + link + "'")) << error;
    EXPECT_TRUE(contains(error, "owned by uid 65534")) << error;
    EXPECT_TRUE(contains(error, "in the shared folder '" + shared + "'")) << error;
    EXPECT_EQ(testing::readFile(victim), "precious");
    EXPECT_EQ(listing(shared), std::vector<std::string>{"frame_0000.png"});
    EXPECT_TRUE(std::filesystem::is_symlink(link));

    // At every link of a chain: our own link to the planted one is refused too.
    const std::string own = shared + "/own.png";
    std::filesystem::create_symlink(link, own);
    EXPECT_TRUE(contains(errorOf([&] { writeTextOutput(own, "png"); }),
                         "refusing to follow the symbolic link '" + link + "'"));
    EXPECT_EQ(testing::readFile(victim), "precious");

    // A link of the current user, or of the folder's owner, is followed.
    ASSERT_EQ(::lchown(link.c_str(), 0, 0), 0);
    writeTextOutput(own, "mine");
    EXPECT_EQ(testing::readFile(victim), "mine");
    const std::string owned = dir + "/owned";
    std::filesystem::create_directories(owned);
    ASSERT_EQ(::chmod(owned.c_str(), 01777), 0);
    ASSERT_EQ(::chown(owned.c_str(), kOtherUser, kOtherUser), 0);
    std::filesystem::create_symlink(victim, owned + "/theirs.png");
    ASSERT_EQ(::lchown((owned + "/theirs.png").c_str(), kOtherUser, kOtherUser), 0);
    writeTextOutput(owned + "/theirs.png", "folder owner's link");
    EXPECT_EQ(testing::readFile(victim), "folder owner's link");

    // Outside sticky world-writable folders the rule does not apply (as in the kernel).
    const std::string open = dir + "/open";
    std::filesystem::create_directories(open);
    ASSERT_EQ(::chmod(open.c_str(), 0777), 0);
    std::filesystem::create_symlink(victim, open + "/x.png");
    ASSERT_EQ(::lchown((open + "/x.png").c_str(), kOtherUser, kOtherUser), 0);
    writeTextOutput(open + "/x.png", "not shared");
    EXPECT_EQ(testing::readFile(victim), "not shared");
}

TEST(OutputFile, FilesAndFifosOfAnotherUserInASharedFolderAreNotReplacedOrWritten) {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a file to another user";
    const std::string shared = sharedFolder(testing::scratchDir());
    const std::string file = testing::writeFile(shared + "/out.png", "theirs");
    ASSERT_EQ(::chown(file.c_str(), kOtherUser, kOtherUser), 0);
    const std::string error = errorOf([&] { writeTextOutput(file, "ours"); });
    EXPECT_TRUE(contains(error, "refusing to replace or write '" + file + "' owned by uid 65534"))
        << error;
    EXPECT_EQ(testing::readFile(file), "theirs");
    // A FIFO: refused before it is opened (which would block and hand the output to its reader).
    const std::string fifo = shared + "/pipe";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0666), 0);
    ASSERT_EQ(::chown(fifo.c_str(), kOtherUser, kOtherUser), 0);
    EXPECT_TRUE(contains(errorOf([&] { writeTextOutput(fifo, "ours"); }), "refusing to replace"));
    EXPECT_EQ(listing(shared), (std::vector<std::string>{"out.png", "pipe"}));
    // The user's own file there is replaced as usual.
    ASSERT_EQ(::chown(file.c_str(), 0, 0), 0);
    writeTextOutput(file, "ours");
    EXPECT_EQ(testing::readFile(file), "ours");
}

TEST(OutputFile, LongNamesFitBecauseTheTemporaryNameIsShort) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/" + std::string(251, 'n') + ".png";  // 255 bytes
    writeTextOutput(path, "x");
    EXPECT_EQ(testing::readFile(path), "x");
}

TEST(OutputFile, FifoIsWrittenInPlace) {
    const std::string dir = testing::scratchDir();
    const std::string fifo = dir + "/pipe";
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::string received;
    std::thread reader([&] { received = testing::readFile(fifo); });
    writeTextOutput(fifo, "through the pipe");
    reader.join();
    EXPECT_EQ(received, "through the pipe");
    struct stat st;
    ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO must not be replaced by a file";
    EXPECT_EQ(listing(dir), std::vector<std::string>{"pipe"});
}

TEST(OutputFile, SocketIsWrittenInPlace) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/sock";
    const int server = ::socket(AF_UNIX, SOCK_STREAM, 0);
    ASSERT_GE(server, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
    ASSERT_EQ(::bind(server, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    ASSERT_EQ(::listen(server, 1), 0);
    std::string received;
    std::thread reader([&] {
        const int c = ::accept(server, nullptr, nullptr);
        char buf[256];
        ssize_t n;
        while ((n = ::read(c, buf, sizeof buf)) > 0) received.append(buf, size_t(n));
        ::close(c);
    });
    writeTextOutput(path, "through the socket");
    reader.join();
    ::close(server);
    EXPECT_EQ(received, "through the socket");
    struct stat st;
    ASSERT_EQ(::lstat(path.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
}

TEST(OutputFile, CharacterDevicesAreWrittenInPlaceAndAFullDeviceIsAnError) {
    writeTextOutput("/dev/null", "discarded");
    struct stat st;
    ASSERT_EQ(::stat("/dev/null", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
    if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    const std::string msg = errorOf([] { writeTextOutput("/dev/full", "no room"); });
    EXPECT_TRUE(contains(msg, "/dev/full: cannot write")) << msg;
    EXPECT_TRUE(contains(msg, "No space left on device")) << msg;
    ASSERT_EQ(::stat("/dev/full", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
}

TEST(OutputFile, FoldersMissingFoldersAndBlockDevicesAreRefused) {
    const std::string dir = testing::scratchDir();
    EXPECT_TRUE(contains(errorOf([&] { resolveOutput(dir); }), "is a folder"));
    EXPECT_TRUE(contains(errorOf([&] { resolveOutput(dir + "/missing/a.png"); }),
                         "folder '" + dir + "/missing' does not exist"));
    EXPECT_TRUE(contains(errorOf([&] { resolveOutput(""); }), "empty output file name"));
    for (const auto& e : std::filesystem::directory_iterator("/dev")) {
        if (!e.is_block_file()) continue;
        EXPECT_TRUE(contains(errorOf([&] { resolveOutput(e.path()); }), "is a block device"));
        break;
    }
}

/// Runs f in a child process whose standard output is a terminal (a pseudo-terminal); returns
/// the child's exit status (f's return value, 99 when f throws something unexpected).
int withTerminalStdout(const std::function<int(const std::string& ttyName)>& f) {
    const int master = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) return -1;
    const std::string name = ::ptsname(master);
    const pid_t pid = ::fork();
    if (pid == 0) {
        const int slave = ::open(name.c_str(), O_RDWR | O_NOCTTY);
        if (slave < 0 || ::dup2(slave, STDOUT_FILENO) < 0) ::_exit(98);
        int code = 99;
        try {
            code = f(name);
        } catch (...) {
        }
        ::_exit(code);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(master);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -2;
}

TEST(OutputFile, TerminalsAreRefused) {
    const int code = withTerminalStdout([](const std::string& tty) {
        const std::string dash = errorOf([] { resolveOutput("-"); });
        const std::string named = errorOf([&] { OutputFile out(tty); });
        return contains(dash, "standard output is a terminal") && contains(named, "is a terminal")
                   ? 0
                   : 1;
    });
    if (code == -1) GTEST_SKIP() << "no pseudo-terminals here";
    EXPECT_EQ(code, 0);
}

TEST(OutputFile, StandardOutputIsWrittenWhenRedirected) {
    const std::string dir = testing::scratchDir();
    const std::string path = dir + "/captured";
    const pid_t pid = ::fork();
    if (pid == 0) {
        const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
        ::dup2(fd, STDOUT_FILENO);
        try {
            writeTextOutput("-", "to stdout");
        } catch (...) {
            ::_exit(1);
        }
        ::_exit(0);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    EXPECT_EQ(testing::readFile(path), "to stdout");
}

TEST(OutputFile, AFileSizeLimitIsAnErrorThatLeavesNothingBehind) {
    // A file-size limit fails writes as a full disk does (EFBIG instead of ENOSPC), in a child so
    // that the limit stays there.
    const std::string dir = testing::scratchDir();
    const std::string path = testing::writeFile(dir + "/out.bin", "old");
    const pid_t pid = ::fork();
    if (pid == 0) {
        installOutputSignalHandlers();  // SIGXFSZ ignored: the write fails instead
        rlimit limit{4096, 4096};
        ::setrlimit(RLIMIT_FSIZE, &limit);
        const std::string msg = errorOf([&] { writeTextOutput(path, std::string(3 << 20, 'x')); });
        ::_exit(contains(msg, "cannot write (after") && contains(msg, "File too large") ? 0 : 1);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0);
    EXPECT_EQ(listing(dir), std::vector<std::string>{"out.bin"});
    EXPECT_EQ(testing::readFile(path), "old");
}

TEST(OutputFile, TerminatingSignalsRemoveTemporaries) {
    const std::string dir = testing::scratchDir();
    for (int sig : {SIGTERM, SIGINT}) {
        const pid_t pid = ::fork();
        if (pid == 0) {
            installOutputSignalHandlers();
            OutputFile out(dir + "/out.bin");
            out.write(std::string(2 << 20, 'x'));
            ::raise(sig);
            ::_exit(0);  // not reached
        }
        int status = 0;
        ::waitpid(pid, &status, 0);
        ASSERT_TRUE(WIFSIGNALED(status)) << "the process ends by the signal";
        EXPECT_EQ(WTERMSIG(status), sig);
        EXPECT_TRUE(listing(dir).empty()) << "signal " << sig << " left " << listing(dir)[0];
    }
}

TEST(OutputFile, OutputsNamingAnInputOrEachOtherAreRefused) {
    const std::string dir = testing::scratchDir();
    const std::string mesh = testing::writeFile(dir + "/mesh.vtk", "mesh");
    std::filesystem::create_symlink(mesh, dir + "/alias.vtk");
    const std::vector<NamedFile> inputs{{"the input mesh", mesh}, {"--tf", "cool-to-warm"}};
    EXPECT_EQ(errorOf([&] { checkOutputsDistinct(inputs, {{"-o", dir + "/a.png"}}); }), "");
    for (const std::string& out :
         {mesh, dir + "/alias.vtk",
          dir + "/../" + std::filesystem::path(dir).filename().string() + "/mesh.vtk"}) {
        const std::string msg = errorOf([&] { checkOutputsDistinct(inputs, {{"-o", out}}); });
        EXPECT_EQ(msg,
                  out + ": -o names the input mesh '" + mesh + "': refusing to overwrite an input");
    }
    EXPECT_EQ(testing::readFile(mesh), "mesh");
    // Two outputs naming one file, existing or not yet, however spelt.
    EXPECT_EQ(
        errorOf([&] {
            checkOutputsDistinct(inputs, {{"-o", dir + "/s.png"}, {"--heatmap", dir + "/./s.png"}});
        }),
        dir + "/./s.png: --heatmap names the same file as -o '" + dir + "/s.png'");
    EXPECT_TRUE(contains(errorOf([&] {
                             checkOutputsDistinct({}, {{"-o", "-"}, {"--stats", "-"}});
                         }),
                         "--stats names the same file as -o"));
    // Discarding twice is fine.
    EXPECT_EQ(errorOf([&] {
                  checkOutputsDistinct(inputs, {{"-o", "/dev/null"}, {"--stats", "/dev/null"}});
              }),
              "");
}

}  // namespace
}  // namespace uvr
