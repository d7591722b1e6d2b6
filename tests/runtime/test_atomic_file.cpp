// writeFileAtomically and readWholeFile (common/runtime/include/omnislam/runtime/atomic_file.h): the bytes
// arrive whole, an old file is replaced by a rename (a reader holding it keeps it whole), and each failing
// step (create in a folder that does not exist or under a regular file, a write cut short by the file size
// limit, a rename onto a folder) throws naming the path, the step and the system's reason, leaves no
// temporary file and leaves the old file as it was.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "omnislam/runtime/atomic_file.h"

using namespace omnislam::runtime;
namespace fs = std::filesystem;

namespace {

struct TmpDir {
  fs::path path = fs::path(::testing::TempDir()) / ("omnislam_atomic_file_" + std::to_string(::getpid()));
  TmpDir() {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TmpDir() { fs::remove_all(path); }
  /// The names in the folder, sorted.
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& e : fs::directory_iterator(path)) n.push_back(e.path().filename().string());
    std::sort(n.begin(), n.end());
    return n;
  }
};

std::string text(const std::vector<std::uint8_t>& b) { return std::string(b.begin(), b.end()); }
void writeText(const std::string& path, const std::string& s) { writeFileAtomically(path, s.data(), s.size()); }

/// The message of the std::runtime_error f throws ("" if it throws none).
template <class F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(AtomicFile, WritesTheBytesWholeAndLeavesOnlyTheTarget) {
  TmpDir dir;
  const std::string path = (dir.path / "state.bin").string();
  std::vector<std::uint8_t> bytes(300'000);  // more than one write(2) may take at once
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 3);
  writeFileAtomically(path, bytes);
  EXPECT_EQ(readWholeFile(path), bytes);
  EXPECT_EQ(dir.names(), std::vector<std::string>{"state.bin"});
  writeText(path, "");
  EXPECT_TRUE(readWholeFile(path).empty()) << "an empty file is a file too";
  writeText(path, "text\n");
  EXPECT_EQ(text(readWholeFile(path)), "text\n");
  EXPECT_EQ(dir.names(), std::vector<std::string>{"state.bin"});
  const std::string relative = errorOf([] { readWholeFile("no_such_file_here"); });
  EXPECT_NE(relative.find("no_such_file_here"), std::string::npos) << relative;
}

// A reader that opened the old file before the replacement still reads the old bytes whole: the new
// file is another inode renamed over the name, never the old one rewritten in place.
TEST(AtomicFile, ReplacesTheOldFileByARename) {
  TmpDir dir;
  const std::string path = (dir.path / "map.yaml").string();
  writeText(path, "the old content, longer than the new\n");
  struct stat before {};
  ASSERT_EQ(::stat(path.c_str(), &before), 0);
  std::ifstream reader(path, std::ios::binary);
  ASSERT_TRUE(reader.good());
  writeText(path, "new\n");
  const std::string old_seen((std::istreambuf_iterator<char>(reader)), std::istreambuf_iterator<char>());
  EXPECT_EQ(old_seen, "the old content, longer than the new\n");
  EXPECT_EQ(text(readWholeFile(path)), "new\n");
  struct stat after {};
  ASSERT_EQ(::stat(path.c_str(), &after), 0);
  EXPECT_NE(after.st_ino, before.st_ino) << "replaced by a rename of another file";
  EXPECT_EQ(dir.names(), std::vector<std::string>{"map.yaml"});
}

// The tests run as root, so a folder without write permission does not fail; a folder that does not exist
// and a "folder" that is a regular file do.
TEST(AtomicFile, AFolderThatCannotHoldTheFileGivesTheStepAndReason) {
  TmpDir dir;
  const std::string missing = (dir.path / "no_such_dir" / "x.ckpt").string();
  const std::string e1 = errorOf([&] { writeText(missing, "x"); });
  EXPECT_EQ(e1, "cannot write '" + missing + "': create: " + std::strerror(ENOENT));
  writeText((dir.path / "plain").string(), "a regular file");
  const std::string under_file = (dir.path / "plain" / "x.ckpt").string();
  const std::string e2 = errorOf([&] { writeText(under_file, "x"); });
  EXPECT_EQ(e2, "cannot write '" + under_file + "': create: " + std::strerror(ENOTDIR));
  EXPECT_EQ(dir.names(), std::vector<std::string>{"plain"});
  EXPECT_EQ(text(readWholeFile((dir.path / "plain").string())), "a regular file");
}

// A write the system cuts short (here the file size limit, RLIMIT_FSIZE, which binds root too; a full
// disk fails the same way with ENOSPC): the temporary file is removed and the old file is untouched.
TEST(AtomicFile, AFailedWriteLeavesTheOldFileAndNoTemporary) {
  TmpDir dir;
  const std::string path = (dir.path / "state.ckpt").string();
  writeText(path, "old");
  rlimit saved{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);  // else the signal ends the process
  rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  const std::string e = errorOf([&] { writeFileAtomically(path, std::vector<std::uint8_t>(100'000, 1)); });
  ::setrlimit(RLIMIT_FSIZE, &saved);
  ::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(e, "cannot write '" + path + "': write: " + std::strerror(EFBIG));
  EXPECT_EQ(text(readWholeFile(path)), "old");
  EXPECT_EQ(dir.names(), std::vector<std::string>{"state.ckpt"});
}

// The last step that can fail before the name changes: a rename onto a folder. The written temporary
// file is removed.
TEST(AtomicFile, AFailedRenameRemovesTheWrittenTemporary) {
  TmpDir dir;
  const fs::path target = dir.path / "taken";
  fs::create_directories(target / "inside");
  const std::string e = errorOf([&] { writeText(target.string(), "x"); });
  EXPECT_EQ(e, "cannot write '" + target.string() + "': rename: " + std::strerror(EISDIR));
  EXPECT_EQ(dir.names(), std::vector<std::string>{"taken"});
  EXPECT_TRUE(fs::is_directory(target / "inside"));
}

}  // namespace
