// The output-file writer and check: a write that fails or is refused leaves the target as it
// was and no temporary beside it; what is not a regular file is refused without being opened.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "flashgs/error.h"
#include "flashgs/file_access.h"
#include "flashgs/file_write.h"

namespace flashgs {
namespace {

namespace fs = std::filesystem;

std::string fresh_dir(const std::string& name) {
  const fs::path dir = fs::path(FLASHGS_TEST_OUTPUT_DIR) / "file_write" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_text(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// The names in `dir`, sorted: a temporary left behind shows here.
std::vector<std::string> names_in(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Points the file's descriptor at /dev/full: from here on its writes fail with ENOSPC, as on a
// full disk.
void fill_the_disk(const OutputFile& file) {
  const int full = ::open("/dev/full", O_WRONLY | O_CLOEXEC);
  ASSERT_GE(full, 0);
  ASSERT_EQ(::dup2(full, file.descriptor()), file.descriptor());
  ::close(full);
}

// The message of the flashgs::Error that `write` throws; empty when it throws none.
template <class Write>
std::string error_of(Write&& write) {
  try {
    write();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(FileWrite, WritesTheWholeFileAndLeavesNoTemporary) {
  const std::string dir = fresh_dir("whole");
  const std::string path = dir + "/out.txt";
  write_file_atomically(path, "first");
  EXPECT_EQ(read_text(path), "first");
  write_file_atomically(path, [](OutputFile& file) {
    file.write("second, ");
    const std::string large(3 << 20, 'x');  // past the buffer: written straight through
    file.write(large);
  });
  EXPECT_EQ(read_text(path).size(), 8u + (3u << 20));
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.txt"});
}

TEST(FileWrite, AWriterThatThrowsLeavesTheOldFileAndNoTemporary) {
  const std::string dir = fresh_dir("throws");
  const std::string path = dir + "/out.txt";
  write_text(path, "old");
  EXPECT_THROW(write_file_atomically(path,
                                     [](OutputFile& file) {
                                       file.write(std::string(2 << 20, 'n'));
                                       throw std::runtime_error("the writer stops");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read_text(path), "old");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.txt"});
  // A file that did not exist does not exist afterwards.
  EXPECT_THROW(write_file_atomically(dir + "/new.txt", [](OutputFile&) { throw std::runtime_error("stop"); }),
               std::runtime_error);
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.txt"});
}

// A full disk, whether the write is large (it fails at once) or small (it fails in the final
// flush, which went unchecked): one message naming the file, not the temporary, and the
// system's reason; the old file stays.
TEST(FileWrite, AFullDiskIsAWriteErrorNamingTheFileAndLeavesTheOldOne) {
  const std::string dir = fresh_dir("full");
  const std::string path = dir + "/out.json";
  write_text(path, "old");
  for (const std::size_t bytes : {std::size_t{4} << 20, std::size_t{10}}) {
    const std::string message = error_of([&] {
      write_file_atomically(path, [&](OutputFile& file) {
        fill_the_disk(file);
        file.write(std::string(bytes, '{'));
      });
    });
    EXPECT_EQ(message, path + ": write error: No space left on device") << bytes << " bytes";
    EXPECT_EQ(read_text(path), "old") << bytes << " bytes";
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"out.json"}) << bytes << " bytes";
  }
}

// A FIFO (opening it blocks until a reader comes), a link to a device, a folder, a dangling
// link and a missing folder: refused with one message, nothing created, the FIFO kept.
TEST(FileWrite, WhatIsNotARegularFileIsRefusedWithoutBeingOpened) {
  const std::string dir = fresh_dir("refused");
  const std::string fifo = dir + "/fifo.png", device = dir + "/full.png", folder = dir + "/folder",
                    dangling = dir + "/dangling.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  // A reader: should the FIFO be opened for writing all the same, the open returns at once and
  // the test fails instead of hanging.
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(reader, 0);
  fs::create_symlink("/dev/full", device);
  fs::create_directories(folder);
  fs::create_symlink(dir + "/nothing_here", dangling);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {fifo, "is a FIFO (named pipe), not a regular file"},
      {device, "is a device, not a regular file"},
      {folder, "is a folder, not a file"},
      {dangling, "a symbolic link whose target does not exist"},
      {dir + "/missing/x.png", "the folder " + dir + "/missing does not exist"},
  };
  for (const auto& [path, problem] : cases) {
    EXPECT_EQ(error_of([&] { check_output_file(path); }), path + ": " + problem);
    EXPECT_EQ(error_of([&] { write_file_atomically(path, "bytes"); }), path + ": " + problem);
  }
  ::close(reader);
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_EQ(names_in(dir), (std::vector<std::string>{"dangling.png", "fifo.png", "folder", "full.png"}));
  EXPECT_EQ(error_of([] { check_output_file(""); }), "the output path is empty");
}

// A link to a regular file is written through: the link stays, the file it names gets the new
// bytes and keeps its permissions.
TEST(FileWrite, ALinkToARegularFileIsWrittenThroughAndStays) {
  const std::string dir = fresh_dir("link");
  fs::create_directories(dir + "/real");
  const std::string real = dir + "/real/out.txt", link = dir + "/link.txt";
  write_text(real, "old");
  fs::permissions(real, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  fs::create_symlink("real/out.txt", link);
  write_file_atomically(link, "new");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(read_text(real), "new");
  EXPECT_EQ(fs::status(real).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(names_in(dir + "/real"), std::vector<std::string>{"out.txt"});
}

}  // namespace
}  // namespace flashgs
