// io::AtomicOutputFile and publish_together: outputs only ever replace
// regular files, never an output another run published meanwhile, appear
// together or not at all, leave no temporary behind a killed run, and a
// failed write to standard output is an error.

#include "geoanchor/io/atomic_file.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/magic.h>
#include <sys/file.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/statfs.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "temp_folder.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::TempFolder;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::vector<std::string> names_in(const fs::path& folder) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(folder)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// The Error `f` throws (code and message), or a failure when it throws none.
struct Thrown {
  std::string code, message;
};
Thrown thrown_by(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return {e.code(), e.what()};
  }
  ADD_FAILURE() << "no geoanchor::Error thrown";
  return {};
}

// Makes `p` older than a stale temporary needs to be.
void age(const fs::path& p) {
  const struct timespec old[2] = {{1000000000, 0}, {1000000000, 0}};  // 2001-09-09
  ASSERT_EQ(::utimensat(AT_FDCWD, p.c_str(), old, AT_SYMLINK_NOFOLLOW), 0) << p << ": " << std::strerror(errno);
}

constexpr char kStaleName[] = ".tile.las.tmp-0123456789abcdef";

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_NothingButARegularFileIsReplacedWithOrWithoutOverwrite) {
  TempFolder dir;
  struct Case {
    std::string name, what;
    std::function<bool(const fs::path&)> make;
  };
  const fs::path elsewhere = dir / "elsewhere";
  fs::create_directory(elsewhere);
  ASSERT_EQ(::mkfifo((elsewhere / "fifo").c_str(), 0644), 0);
  const std::vector<Case> cases = {
      {"fifo.csv", "a FIFO (named pipe)", [](const fs::path& p) { return ::mkfifo(p.c_str(), 0644) == 0; }},
      {"folder.csv", "a folder", [](const fs::path& p) { return fs::create_directory(p); }},
      // The device /dev/null is (1, 3); made in the test's folder, never /dev itself.
      {"null.csv", "a character device",
       [](const fs::path& p) { return ::mknod(p.c_str(), S_IFCHR | 0644, ::makedev(1, 3)) == 0; }},
      {"socket.csv", "a socket",
       [](const fs::path& p) {
         // Bound by its name inside the folder: the whole path may not fit sun_path.
         const fs::path cwd = fs::current_path();
         fs::current_path(p.parent_path());
         const int s = ::socket(AF_UNIX, SOCK_STREAM, 0);
         sockaddr_un a{};
         a.sun_family = AF_UNIX;
         std::snprintf(a.sun_path, sizeof a.sun_path, "%s", p.filename().c_str());
         const bool ok = s >= 0 && ::bind(s, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
         if (s >= 0) ::close(s);
         fs::current_path(cwd);
         return ok;
       }},
      {"dangling.csv", "a dangling symbolic link",
       [&](const fs::path& p) { return ::symlink((dir / "nowhere").c_str(), p.c_str()) == 0; }},
      {"to_fifo.csv", "a symbolic link to a FIFO (named pipe)",
       [&](const fs::path& p) { return ::symlink((elsewhere / "fifo").c_str(), p.c_str()) == 0; }},
  };
  for (const auto& c : cases) {
    const fs::path p = dir / c.name;
    if (!c.make(p)) {
      // mknod needs CAP_MKNOD: without it there is no device to test with here.
      EXPECT_EQ(c.name, "null.csv") << "cannot make " << p << ": " << std::strerror(errno);
      continue;
    }
    const auto type_before = fs::symlink_status(p).type();
    for (const io::Overwrite o : {io::Overwrite::allow, io::Overwrite::refuse}) {
      const Thrown t = thrown_by([&] { io::AtomicOutputFile out(p, o); });
      EXPECT_EQ(t.code, "E_OUTPUT_NOT_REGULAR") << c.name;
      EXPECT_NE(t.message.find(p.string() + ": is " + c.what + ", not a regular file"), std::string::npos) << t.message;
      EXPECT_NE(t.message.find("with or without --overwrite"), std::string::npos) << t.message;
      EXPECT_EQ(fs::symlink_status(p).type(), type_before) << c.name << " was replaced";
    }
  }
  // Nothing else was created: no temporary, no output.
  std::vector<std::string> expected = {"dangling.csv", "elsewhere", "fifo.csv", "folder.csv", "socket.csv", "to_fifo.csv"};
  if (fs::exists(fs::symlink_status(dir / "null.csv"))) expected.insert(expected.begin() + 4, "null.csv");
  EXPECT_EQ(names_in(dir.path()), expected);
  EXPECT_TRUE(fs::is_empty(dir / "folder.csv"));
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_ALinkToARegularFileIsReplacedItselfItsTargetNeverWritten) {
  TempFolder dir;
  fs::create_directory(dir / "elsewhere");
  put(dir / "elsewhere" / "target.csv", "the target\n");
  ASSERT_EQ(::symlink((dir / "elsewhere" / "target.csv").c_str(), (dir / "link.csv").c_str()), 0);
  EXPECT_EQ(thrown_by([&] { io::AtomicOutputFile out(dir / "link.csv", io::Overwrite::refuse); }).code, "E_OUTPUT_EXISTS");
  {
    io::AtomicOutputFile out(dir / "link.csv", io::Overwrite::allow);
    out.stream() << "new output\n";
    out.commit();
  }
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir / "link.csv")));
  EXPECT_EQ(slurp(dir / "link.csv"), "new output\n");
  EXPECT_EQ(slurp(dir / "elsewhere" / "target.csv"), "the target\n");
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_AnOutputPublishedMeanwhileIsNeverReplacedWithoutOverwrite) {
  TempFolder dir;
  const fs::path p = dir / "tile.csv";
  // Two runs opened the same absent output; the first publishes it.
  io::AtomicOutputFile first(p, io::Overwrite::refuse);
  io::AtomicOutputFile second(p, io::Overwrite::refuse);
  first.stream() << "first run\n";
  second.stream() << "second run\n";
  first.commit();
  const Thrown t = thrown_by([&] { second.commit(); });
  EXPECT_EQ(t.code, "E_OUTPUT_EXISTS");
  EXPECT_NE(t.message.find(p.string() + ": another process put a file at this path while this run was writing it"),
            std::string::npos)
      << t.message;
  EXPECT_EQ(slurp(p), "first run\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"tile.csv"});  // the loser's temporary is gone too
  // With --overwrite the later one replaces it, as asked.
  io::AtomicOutputFile third(p, io::Overwrite::allow);
  third.stream() << "third run\n";
  third.commit();
  EXPECT_EQ(slurp(p), "third run\n");
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"tile.csv"});
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_AFifoThatAppearsBeforeTheCommitIsRefusedEvenWithOverwrite) {
  TempFolder dir;
  put(dir / "tile.csv", "old tile\n");
  put(dir / "tile.csv.geoanchor.json", "old sidecar\n");
  io::AtomicOutputFile side(dir / "tile.csv.geoanchor.json", io::Overwrite::allow);
  io::AtomicOutputFile tile(dir / "tile.csv", io::Overwrite::allow);
  side.stream() << "new sidecar\n";
  tile.stream() << "new tile\n";
  fs::remove(dir / "tile.csv");
  ASSERT_EQ(::mkfifo((dir / "tile.csv").c_str(), 0644), 0);
  const Thrown t = thrown_by([&] { io::publish_together({&side, &tile}); });
  EXPECT_EQ(t.code, "E_OUTPUT_NOT_REGULAR");
  EXPECT_NE(t.message.find("neither " + (dir / "tile.csv.geoanchor.json").string() + " nor " + (dir / "tile.csv").string() +
                           " was written"),
            std::string::npos)
      << t.message;
  EXPECT_TRUE(fs::is_fifo(dir / "tile.csv"));
  EXPECT_EQ(slurp(dir / "tile.csv.geoanchor.json"), "old sidecar\n");  // nothing was published
  EXPECT_EQ(names_in(dir.path()), (std::vector<std::string>{"tile.csv", "tile.csv.geoanchor.json"}));
}

// Runs `f` with writes to regular files limited to `bytes` (RLIMIT_FSIZE; a
// write past it fails with EFBIG, as on a full disk), then lifts the limit.
void with_file_size_limit(rlim_t bytes, const std::function<void()>& f) {
  struct rlimit saved {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  struct rlimit limited = saved;
  limited.rlim_cur = bytes;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  try {
    f();
  } catch (...) {
    ::setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, old_handler);
    throw;
  }
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, old_handler);
}

constexpr rlim_t kFileSizeLimit_bytes = 4096;  // above the small file of each pair, below the large one

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_APairOneOfWhichCannotBeWrittenLeavesNeitherAndARerunWritesBoth) {
  TempFolder dir;
  const std::string small(100, 's'), large(3 * kFileSizeLimit_bytes, 'L');
  for (const bool sidecar_too_large : {true, false}) {
    SCOPED_TRACE(sidecar_too_large ? "the sidecar cannot be written" : "the tile cannot be written");
    Thrown t;
    with_file_size_limit(kFileSizeLimit_bytes, [&] {
      io::AtomicOutputFile side(dir / "tile.csv.geoanchor.json", io::Overwrite::refuse);
      io::AtomicOutputFile tile(dir / "tile.csv", io::Overwrite::refuse);
      side.stream() << (sidecar_too_large ? large : small);
      tile.stream() << (sidecar_too_large ? small : large);
      t = thrown_by([&] { io::publish_together({&side, &tile}); });
    });
    EXPECT_EQ(t.code, "E_WRITE");
    const std::string failed = sidecar_too_large ? "tile.csv.geoanchor.json" : "tile.csv";
    EXPECT_NE(t.message.find((dir / failed).string() + ": writing failed (File too large); neither " +
                             (dir / "tile.csv.geoanchor.json").string() + " nor " + (dir / "tile.csv").string() +
                             " was written"),
              std::string::npos)
        << t.message;
    EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{}) << "left behind";
  }
  // The rerun is not blocked by anything: both written.
  io::AtomicOutputFile side(dir / "tile.csv.geoanchor.json", io::Overwrite::refuse);
  io::AtomicOutputFile tile(dir / "tile.csv", io::Overwrite::refuse);
  side.stream() << large;
  tile.stream() << small;
  io::publish_together({&side, &tile});
  EXPECT_EQ(slurp(dir / "tile.csv"), small);
  EXPECT_EQ(slurp(dir / "tile.csv.geoanchor.json"), large);
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_APairThatLosesItsTileToAnotherRunTakesItsSidecarBack) {
  TempFolder dir;
  io::AtomicOutputFile side(dir / "tile.csv.geoanchor.json", io::Overwrite::refuse);
  io::AtomicOutputFile tile(dir / "tile.csv", io::Overwrite::refuse);
  side.stream() << "this run's sidecar\n";
  tile.stream() << "this run's tile\n";
  {
    // Another run publishes the tile between this one's check and its publication.
    io::AtomicOutputFile other(dir / "tile.csv", io::Overwrite::refuse);
    other.stream() << "the other run's tile\n";
    other.commit();
  }
  const Thrown t = thrown_by([&] { io::publish_together({&side, &tile}); });
  EXPECT_EQ(t.code, "E_OUTPUT_EXISTS");
  EXPECT_EQ(slurp(dir / "tile.csv"), "the other run's tile\n");
  // This run's sidecar, published first, was taken back: it never stands
  // beside the other run's tile.
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"tile.csv"});
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_StaleTemporariesAreRemovedLiveOnesAndOthersKept) {
  TempFolder dir;
  // A live writer's temporary, as old as a stale one (a sidecar's waits,
  // untouched, while its tile is computed).
  io::AtomicOutputFile live(dir / "live.las", io::Overwrite::refuse);
  live.stream() << "still being written";
  age(live.temporary_path());
  put(dir / kStaleName, "left by a killed run");
  age(dir / kStaleName);
  // Unlocked but recent: the instant between creating and locking.
  put(dir / ".fresh.las.tmp-00000000000000ff", "just created");
  // Not ours, or not files: never touched.
  const std::vector<std::string> others = {".x.tmp-0123",         ".tile.las.tmp-0123456789ABCDEF", ".tmp-0123456789abcdef",
                                           "tile.las.tmp-0123456789abcdef", ".tile.las.tmp-0123456789abcdeg"};
  for (const auto& n : others) {
    put(dir / n, "someone else's");
    age(dir / n);
  }
  fs::create_directory(dir / ".folder.tmp-0123456789abcdef");
  age(dir / ".folder.tmp-0123456789abcdef");
  ASSERT_EQ(::symlink((dir / kStaleName).c_str(), (dir / ".link.tmp-0123456789abcdef").c_str()), 0);
  age(dir / ".link.tmp-0123456789abcdef");

  const std::vector<fs::path> removed = io::remove_stale_temporaries(dir.path());
  EXPECT_EQ(removed, std::vector<fs::path>{dir / kStaleName});
  EXPECT_FALSE(fs::exists(dir / kStaleName));
  EXPECT_TRUE(fs::exists(live.temporary_path()));
  EXPECT_TRUE(fs::exists(dir / ".fresh.las.tmp-00000000000000ff"));
  for (const auto& n : others) EXPECT_TRUE(fs::exists(dir / n)) << n;
  EXPECT_TRUE(fs::is_directory(dir / ".folder.tmp-0123456789abcdef"));
  EXPECT_TRUE(fs::is_symlink(dir / ".link.tmp-0123456789abcdef"));
  live.commit();
  EXPECT_EQ(slurp(dir / "live.las"), "still being written");
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_TheFirstOutputOpenedInAFolderRemovesItsStaleTemporaries) {
  TempFolder dir;
  put(dir / kStaleName, "left by a killed run");
  age(dir / kStaleName);
  io::AtomicOutputFile out(dir / "tile.las", io::Overwrite::refuse);
  EXPECT_FALSE(fs::exists(dir / kStaleName));
  out.stream() << "x";
  out.commit();
  EXPECT_EQ(names_in(dir.path()), std::vector<std::string>{"tile.las"});
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_ASidecarHeldByItsPublisherIsNotRemovedAsAnOrphan) {
  TempFolder dir;
  put(dir / "held.json", "being published");
  const int fd = ::open((dir / "held.json").c_str(), O_RDONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX), 0);
  EXPECT_FALSE(io::remove_unless_held(dir / "held.json"));
  EXPECT_TRUE(fs::exists(dir / "held.json"));
  ::close(fd);
  EXPECT_TRUE(io::remove_unless_held(dir / "held.json"));
  EXPECT_FALSE(fs::exists(dir / "held.json"));
  EXPECT_TRUE(io::remove_unless_held(dir / "held.json"));  // nothing there
}

// issue 12 point 11
TEST(AtomicOutputFile, Issue12Point11_AFailedWriteToStandardOutputIsAnError) {
  std::cout.flush();
  std::fflush(stdout);
  const int saved = ::dup(STDOUT_FILENO);
  const int full = ::open("/dev/full", O_WRONLY);
  ASSERT_GE(saved, 0);
  ASSERT_GE(full, 0);
  ASSERT_EQ(::dup2(full, STDOUT_FILENO), STDOUT_FILENO);
  ::close(full);
  std::cout << "a report nobody will read\n";
  const Thrown t = thrown_by([] { io::finish_standard_output("the report", "; nothing else was written"); });
  ::dup2(saved, STDOUT_FILENO);
  ::close(saved);
  std::clearerr(stdout);
  std::cout.clear();
  EXPECT_EQ(t.code, "E_WRITE");
  EXPECT_EQ(t.message, "standard output: the report could not be written (No space left on device); nothing else was written");
  EXPECT_NO_THROW(io::finish_standard_output("nothing"));
}

// issue 12 point 13: a large output leaves the page cache stretch by
// stretch as it is written, and what is published is every byte, in place,
// including a stretch rewritten after a seek back (as the LAS writer
// rewrites its header). The bytes are made from their offsets, so neither
// side is held whole.
TEST(AtomicOutputFile, Issue12Point13_ALargeOutputLeavesTheCacheAsItGoesAndIsPublishedByteForByte) {
  TempFolder dir;
  constexpr std::size_t kBytes = 160u << 20;  // ten of the writer's 16 MB stretches
  constexpr std::size_t kHeaderAt = 1000;
  const std::string header = "a header written last";
  const auto byte_at = [](std::size_t i) {  // splitmix64 of the 8-byte word, then the byte
    std::uint64_t z = (i / 8) * 0x9e3779b97f4a7c15ull + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return static_cast<char>(z >> (8 * (i % 8)));
  };
  {
    io::AtomicOutputFile out(dir / "big.bin", io::Overwrite::refuse);
    std::string chunk;
    std::size_t at = 0, size = 1;
    while (at < kBytes) {  // writes of 1, 4, 13, 40, ... bytes, up to 8 MB, then again
      const std::size_t n = std::min(size, kBytes - at);
      chunk.resize(n);
      for (std::size_t k = 0; k < n; ++k) chunk[k] = byte_at(at + k);
      out.stream().write(chunk.data(), static_cast<std::streamsize>(n));
      at += n;
      size = size >= (8u << 20) ? 1 : size * 3 + 1;
    }
    out.stream().seekp(static_cast<std::streamoff>(kHeaderAt));
    out.stream().write(header.data(), static_cast<std::streamsize>(header.size()));
    out.commit();
  }
  const fs::path path = dir / "big.bin";
  ASSERT_EQ(fs::file_size(path), kBytes);
  // What of it is still in the page cache: the last stretches only (tmpfs,
  // which keeps its files in memory, ignores the hint).
  {
    const int fd = ::open(path.c_str(), O_RDONLY);
    ASSERT_GE(fd, 0);
    struct statfs fs_info {};
    ASSERT_EQ(::fstatfs(fd, &fs_info), 0);
    void* map = ::mmap(nullptr, kBytes, PROT_READ, MAP_SHARED, fd, 0);
    ASSERT_NE(map, MAP_FAILED);
    const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    std::vector<unsigned char> resident((kBytes + page - 1) / page);
    ASSERT_EQ(::mincore(map, kBytes, resident.data()), 0);
    ::munmap(map, kBytes);
    ::close(fd);
    const std::size_t cached_bytes =
        page * static_cast<std::size_t>(std::count_if(resident.begin(), resident.end(), [](unsigned char r) { return r & 1; }));
    constexpr std::size_t kCachedAtMost = 64u << 20;  // the last stretches and a margin, of 160 MB
    if (fs_info.f_type != TMPFS_MAGIC) {
      EXPECT_LE(cached_bytes, kCachedAtMost) << "of " << kBytes << " bytes";
    }
  }
  std::ifstream in(path, std::ios::binary);
  std::string block(1u << 20, '\0');
  std::size_t at = 0, differ_at = kBytes;
  while (at < kBytes && differ_at == kBytes) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    ASSERT_EQ(static_cast<std::size_t>(in.gcount()), block.size()) << "at byte " << at;
    for (std::size_t k = 0; k < block.size(); ++k) {
      const std::size_t i = at + k;
      const char want = i >= kHeaderAt && i < kHeaderAt + header.size() ? header[i - kHeaderAt] : byte_at(i);
      if (block[k] != want) {
        differ_at = i;
        break;
      }
    }
    at += block.size();
  }
  EXPECT_EQ(differ_at, kBytes) << "first difference at byte " << differ_at;
}

}  // namespace
}  // namespace geoanchor
