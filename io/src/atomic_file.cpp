#include "geoanchor/io/atomic_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <signal.h>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <mutex>
#include <random>
#include <set>
#include <stdexcept>

#include "geoanchor/base/error.hpp"

namespace geoanchor::io {
namespace {

namespace fs = std::filesystem;

// A fixed table of temporary paths that a signal handler may read. A slot is
// claimed, its path copied, and only then published as ready; the handler
// reads ready slots only, so it never sees a half-written path.
constexpr int kSlots = 16;
constexpr std::size_t kPathMax = 4096;
struct Slot {
  std::atomic<bool> claimed{false};
  std::atomic<bool> ready{false};
  char path[kPathMax] = {};
};
std::array<Slot, kSlots> g_temp_registry;  // NOLINT: signal handlers need a global

int register_temp(const fs::path& p) {
  const std::string s = p.string();
  if (s.size() >= kPathMax) return -1;
  for (int i = 0; i < kSlots; ++i) {
    auto& slot = g_temp_registry[static_cast<std::size_t>(i)];
    bool expected = false;
    if (!slot.claimed.compare_exchange_strong(expected, true)) continue;
    std::memcpy(slot.path, s.c_str(), s.size() + 1);
    slot.ready.store(true);
    return i;
  }
  return -1;  // more than kSlots outputs open at once: still removed on exceptions, not on signals
}

void unregister_temp(int i) {
  if (i < 0) return;
  auto& slot = g_temp_registry[static_cast<std::size_t>(i)];
  slot.ready.store(false);
  slot.claimed.store(false);
}

extern "C" void cleanup_and_reraise(int sig) {
  for (auto& slot : g_temp_registry) {
    if (slot.ready.load()) ::unlink(slot.path);
  }
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

constexpr std::size_t kSuffixDigits = 16;
constexpr std::string_view kTempInfix = ".tmp-";

std::string random_suffix() {
  std::random_device rd;
  const auto v = (static_cast<unsigned long long>(rd()) << 32) ^ rd();
  char buf[kSuffixDigits + 1];
  std::snprintf(buf, sizeof buf, "%016llx", v);
  return buf;
}

std::string reason(int err) { return err != 0 ? std::string(std::strerror(err)) : std::string("unknown error"); }

// What a non-regular file is, in words.
std::string kind_of(const struct stat& st) {
  if (S_ISDIR(st.st_mode)) return "a folder";
  if (S_ISCHR(st.st_mode)) return "a character device";
  if (S_ISBLK(st.st_mode)) return "a block device";
  if (S_ISFIFO(st.st_mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(st.st_mode)) return "a socket";
  if (S_ISLNK(st.st_mode)) return "a symbolic link";
  return "not a regular file";
}

// Empty when `p` is absent, a regular file or a link to one; else what it is.
// `exists` says whether anything is there.
std::string not_regular(const fs::path& p, bool& exists) {
  struct stat st {};
  exists = false;
  if (::lstat(p.c_str(), &st) != 0) return {};  // absent (or unreachable: creating the temporary will say why)
  exists = true;
  if (S_ISREG(st.st_mode)) return {};
  if (!S_ISLNK(st.st_mode)) return kind_of(st);
  struct stat target {};
  if (::stat(p.c_str(), &target) != 0) {
    const int err = errno;
    return err == ENOENT ? std::string("a dangling symbolic link") : "a symbolic link that cannot be followed (" + reason(err) + ")";
  }
  if (S_ISREG(target.st_mode)) return {};
  return "a symbolic link to " + kind_of(target);
}

// Unlinks `p` if it is still the file (device, inode) this process published there.
void unlink_if_same(const fs::path& p, dev_t dev, ino_t ino) {
  struct stat st {};
  if (::lstat(p.c_str(), &st) == 0 && st.st_dev == dev && st.st_ino == ino) ::unlink(p.c_str());
}

// The folders already cleaned of stale temporaries by this process.
std::mutex g_cleaned_mutex;          // NOLINT: one process-wide record, like the signal registry
std::set<std::string> g_cleaned;     // NOLINT
std::vector<fs::path> g_removed_automatically;  // NOLINT: what remove_stale_temporaries_once removed, not yet taken

std::string folder_key(const fs::path& folder) {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(folder, ec);
  return (ec ? folder : canonical).string();
}

void remove_stale_temporaries_once(const fs::path& folder) {
  {
    const std::lock_guard<std::mutex> lock(g_cleaned_mutex);
    if (g_cleaned.count(folder_key(folder)) != 0) return;
  }
  const std::vector<fs::path> removed = remove_stale_temporaries(folder);
  const std::lock_guard<std::mutex> lock(g_cleaned_mutex);
  g_removed_automatically.insert(g_removed_automatically.end(), removed.begin(), removed.end());
}

// A filebuf that keeps the errno of its first failed write, so that the
// error names the cause (disk full, file too large, ...) and not whatever
// a later call left in errno.
//
// It also starts the disk writes of a large output while it is still being
// written: every kWritebackBytes it asks the kernel to begin writing what
// it holds (sync_file_range without waiting), so that the fsync before
// publishing waits for the last stretches only, not for the whole file (a
// fit of 10⁶ marks writes 450 MB), and it waits for the stretch before the
// last and drops it from the page cache (posix_fadvise), so that a large
// output keeps reusing the same few stretches of memory (the benchmark's
// runs of `geoanchor fit` on 10⁶ marks: the write 0.84–1.13 s before,
// 0.54–0.63 s after; the whole command 2.8–3.1 s before, 2.3–2.6 s after).
// Both are hints: a filesystem without them (tmpfs ignores the second) is
// written as without them. A write error they meet is kept like any other
// (the wait reports it here, and the fsync on the same descriptor would
// then no longer see it).
class CheckedFileBuf : public std::filebuf {
 public:
  int first_error() const { return first_errno_; }
  // The descriptor writeback is started on (the same file); -1: none.
  void start_writeback_on(int fd) { writeback_fd_ = fd; }

 protected:
  int_type overflow(int_type c) override {
    errno = 0;
    const int_type r = std::filebuf::overflow(c);
    if (traits_type::eq_int_type(r, traits_type::eof()) && !traits_type::eq_int_type(c, traits_type::eof())) note();
    wrote(1);
    return r;
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    errno = 0;
    const std::streamsize r = std::filebuf::xsputn(s, n);
    if (r < n) note();
    wrote(r);
    return r;
  }
  int sync() override {
    errno = 0;
    const int r = std::filebuf::sync();
    if (r != 0) note();
    return r;
  }
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    errno = 0;
    const pos_type r = std::filebuf::seekoff(off, dir, which);
    if (r == pos_type(off_type(-1))) note();
    return r;
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    errno = 0;
    const pos_type r = std::filebuf::seekpos(pos, which);
    if (r == pos_type(off_type(-1))) note();
    return r;
  }

 private:
  static constexpr std::streamsize kWritebackBytes = 16 << 20;
  void note() {
    if (first_errno_ == 0) first_errno_ = errno != 0 ? errno : EIO;
  }
  void wrote(std::streamsize n) {
    written_ += std::max<std::streamsize>(n, 0);
    if (writeback_fd_ < 0 || written_ - marked_ < kWritebackBytes) return;
    // Hints: where they are not supported the fsync does all the work, as
    // without them. The disk's errors are the write's.
    const int saved = errno;
    const auto keep_write_error = [&](int r) {
      if (r != 0 && (errno == EIO || errno == ENOSPC || errno == EDQUOT || errno == EFBIG)) note();
    };
    keep_write_error(::sync_file_range(writeback_fd_, 0, 0, SYNC_FILE_RANGE_WRITE));
    // The stretch before the last one is on disk by now (or soon): its
    // pages leave the cache, and the next stretches' pages are those just
    // freed. A large output thus holds a few stretches of the cache, not
    // the whole file (on this platform fresh pages cost more than the
    // bytes copied into them; the file is read back from disk if at all).
    if (marked_ > dropped_) {
      keep_write_error(::sync_file_range(writeback_fd_, dropped_, marked_ - dropped_,
                                         SYNC_FILE_RANGE_WAIT_BEFORE | SYNC_FILE_RANGE_WRITE | SYNC_FILE_RANGE_WAIT_AFTER));
      (void)::posix_fadvise(writeback_fd_, dropped_, marked_ - dropped_, POSIX_FADV_DONTNEED);
      dropped_ = marked_;
    }
    marked_ = written_;
    errno = saved;
  }
  int first_errno_ = 0;
  int writeback_fd_ = -1;
  // Bytes written (a lower bound: characters put straight into the buffer
  // are not counted), the count at the last writeback hint, and
  // the bytes from the start whose pages were dropped from the cache;
  // offsets as far as the writer writes in order (a seek only makes a hint
  // miss).
  off_t written_ = 0, marked_ = 0, dropped_ = 0;
};

}  // namespace

struct AtomicOutputFile::State {
  CheckedFileBuf buf;
  std::ostream out{&buf};
  int lock_fd = -1;  // O_WRONLY on the temporary, flock'ed: the claim that it is alive; also what fsync uses
  dev_t dev = 0;
  ino_t ino = 0;
  bool written = false;    // flushed, closed and fsync'ed
  bool published = false;  // at its final path
  bool removed = false;    // temporary gone
};

void install_signal_cleanup() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, cleanup_and_reraise);
  // A closed pipe (`| head`) and a file-size limit kill by default too; a
  // parent that ignores them (the writes then fail and are reported) keeps
  // its choice.
  for (int sig : {SIGPIPE, SIGXFSZ}) {
    struct sigaction current {};
    if (::sigaction(sig, nullptr, &current) == 0 && current.sa_handler == SIG_DFL) std::signal(sig, cleanup_and_reraise);
  }
}

void refuse_same_file(const std::filesystem::path& input, const std::filesystem::path& output) {
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec)) {
    throw Error(ErrorKind::usage, "E_OUTPUT_IS_INPUT",
                output.string() + ": the output would be the input file; the input is never modified, choose another "
                                  "output");
  }
}

void check_output_path(const std::filesystem::path& path, Overwrite overwrite) {
  bool exists = false;
  const std::string what = not_regular(path, exists);
  if (!what.empty()) {
    throw Error(ErrorKind::io, "E_OUTPUT_NOT_REGULAR",
                path.string() + ": is " + what + ", not a regular file; an output only ever replaces a regular file, " +
                    "with or without --overwrite: choose another output path");
  }
  if (exists && overwrite == Overwrite::refuse) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS", path.string() + ": output already exists; pass --overwrite to replace it");
  }
}

bool is_temporary_name(std::string_view name) {
  const std::size_t tail = kTempInfix.size() + kSuffixDigits;
  if (name.size() < 2 + tail || name.front() != '.') return false;
  if (name.substr(name.size() - tail, kTempInfix.size()) != kTempInfix) return false;
  for (char c : name.substr(name.size() - kSuffixDigits)) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& folder) {
  {
    const std::lock_guard<std::mutex> lock(g_cleaned_mutex);
    g_cleaned.insert(folder_key(folder));
  }
  std::vector<fs::path> removed;
  std::error_code ec;
  fs::directory_iterator it(folder.empty() ? fs::path(".") : folder, ec);
  if (ec) return removed;
  std::timespec now{};
  std::timespec_get(&now, TIME_UTC);
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const fs::path p = it->path();
    if (!is_temporary_name(p.filename().string())) continue;
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid()) continue;
    const double age_s = static_cast<double>(now.tv_sec - st.st_mtim.tv_sec) +
                         1e-9 * static_cast<double>(now.tv_nsec - st.st_mtim.tv_nsec);
    if (!(age_s >= static_cast<double>(kStaleTemporaryAge.count()))) continue;  // recent, or dated in the future
    const int fd = ::open(p.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
    if (fd < 0) continue;
    struct stat opened {};
    // Its writer holds LOCK_EX while it lives: taking the lock means none does.
    if (::fstat(fd, &opened) == 0 && opened.st_dev == st.st_dev && opened.st_ino == st.st_ino &&
        ::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      struct stat again {};
      if (::lstat(p.c_str(), &again) == 0 && again.st_dev == st.st_dev && again.st_ino == st.st_ino &&
          ::unlink(p.c_str()) == 0) {
        removed.push_back(p);
      }
    }
    ::close(fd);
  }
  return removed;
}

std::vector<std::filesystem::path> take_removed_stale_temporaries() {
  const std::lock_guard<std::mutex> lock(g_cleaned_mutex);
  std::vector<fs::path> out;
  out.swap(g_removed_automatically);
  return out;
}

std::string stale_temporary_warning(const std::filesystem::path& path) {
  return path.string() + ": removed, a temporary output left by a run that was killed";
}

bool remove_unless_held(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) return errno == ENOENT;
  bool removed = false;
  struct stat opened {};
  if (::fstat(fd, &opened) == 0 && ::flock(fd, LOCK_EX | LOCK_NB) == 0) {
    struct stat st {};
    removed = ::lstat(path.c_str(), &st) != 0 ||
              (st.st_dev == opened.st_dev && st.st_ino == opened.st_ino && ::unlink(path.c_str()) == 0);
  }
  ::close(fd);
  return removed;
}

AtomicOutputFile::AtomicOutputFile(std::filesystem::path final_path, Overwrite overwrite)
    : final_path_(std::move(final_path)), overwrite_(overwrite), s_(std::make_unique<State>()) {
  check_output_path(final_path_, overwrite_);
  std::error_code ec;
  const auto dir = final_path_.has_parent_path() ? final_path_.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(dir, ec)) {
    throw Error(ErrorKind::io, "E_OUTPUT_DIR", final_path_.string() + ": folder " + dir.string() + " does not exist");
  }
  remove_stale_temporaries_once(dir);
  std::string temp_name = ".";
  temp_name.append(final_path_.filename().string()).append(kTempInfix).append(random_suffix());
  temp_path_ = dir / temp_name;
  registry_slot_ = register_temp(temp_path_);
  const int fd = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int err = errno;
    unregister_temp(registry_slot_);
    s_->removed = true;
    throw Error(ErrorKind::io, "E_OUTPUT_OPEN", temp_path_.string() + ": cannot create temporary output: " + reason(err));
  }
  s_->lock_fd = fd;
  // Where the filesystem has no locks the temporary is simply never taken
  // for stale by remove_stale_temporaries().
  (void)::flock(fd, LOCK_EX | LOCK_NB);
  struct stat st {};
  if (::fstat(fd, &st) == 0) {
    s_->dev = st.st_dev;
    s_->ino = st.st_ino;
  }
  if (s_->buf.open(temp_path_, std::ios::out | std::ios::binary | std::ios::trunc) == nullptr) {
    const int err = errno;
    ::close(fd);
    s_->lock_fd = -1;
    ::unlink(temp_path_.c_str());
    s_->removed = true;
    unregister_temp(registry_slot_);
    throw Error(ErrorKind::io, "E_OUTPUT_OPEN", temp_path_.string() + ": cannot open temporary output: " + reason(err));
  }
  s_->buf.start_writeback_on(fd);
}

AtomicOutputFile::~AtomicOutputFile() {
  if (!committed_) {
    s_->buf.close();
    if (!s_->published && !s_->removed) ::unlink(temp_path_.c_str());
  }
  s_->buf.start_writeback_on(-1);
  if (s_->lock_fd >= 0) ::close(s_->lock_fd);
  unregister_temp(registry_slot_);
}

std::ostream& AtomicOutputFile::stream() { return s_->out; }

void AtomicOutputFile::commit() { publish_together({this}); }

void publish_together(std::initializer_list<AtomicOutputFile*> outputs) { publish_together(std::vector<AtomicOutputFile*>(outputs)); }

void publish_together(const std::vector<AtomicOutputFile*>& outputs) {
  const std::vector<AtomicOutputFile*>& v = outputs;
  for (const auto* f : v) {
    if (f->committed_ || f->s_->published || f->s_->removed) throw std::logic_error("publish_together: an output was already committed");
  }
  std::string names;
  const char* last_joint = v.size() == 2 ? " nor " : " and ";
  for (std::size_t k = 0; k < v.size(); ++k) {
    names += (k == 0 ? "" : k + 1 == v.size() ? last_joint : ", ") + v[k]->final_path_.string();
  }
  const std::string none_left = v.size() > 2 ? "none of " + names + " was written"
                                : v.size() == 2 ? "neither " + names + " was written"
                                                : "no output was left";
  // Temporaries removed and published outputs taken back: nothing of this group remains.
  auto roll_back = [&] {
    for (auto* f : v) {
      f->s_->buf.close();
      if (f->s_->published) {
        unlink_if_same(f->final_path_, f->s_->dev, f->s_->ino);
        f->s_->published = false;
      }
      if (!f->s_->removed) ::unlink(f->temp_path_.c_str());
      f->s_->removed = true;
    }
  };

  // 1. Every output written completely and on disk before any is published.
  for (auto* f : v) {
    auto& s = *f->s_;
    s.out.flush();
    int err = s.buf.first_error();
    bool ok = static_cast<bool>(s.out) && err == 0;
    if (s.buf.close() == nullptr) ok = false;
    if (err == 0 && !ok) err = s.buf.first_error() != 0 ? s.buf.first_error() : errno;
    if (ok && ::fsync(s.lock_fd) != 0) {
      ok = false;
      err = errno;
    }
    if (!ok) {
      roll_back();
      throw Error(ErrorKind::io, "E_WRITE",
                  f->final_path_.string() + ": writing failed (" + reason(err) + "); " + none_left);
    }
    s.written = true;
  }
  // 2. With --overwrite: the final paths still hold regular files (or nothing).
  for (auto* f : v) {
    if (f->overwrite_ != Overwrite::allow) continue;
    try {
      check_output_path(f->final_path_, Overwrite::allow);
    } catch (const Error& e) {
      roll_back();
      throw Error(e.kind(), e.code(), std::string(e.what()) + "; " + none_left);
    }
  }
  // 3. No old last output beside new earlier ones.
  if (v.size() > 1 && v.back()->overwrite_ == Overwrite::allow) {
    if (::unlink(v.back()->final_path_.c_str()) != 0 && errno != ENOENT) {
      const int err = errno;
      roll_back();
      throw Error(ErrorKind::io, "E_RENAME",
                  v.back()->final_path_.string() + ": cannot remove the old output before replacing it: " + reason(err) +
                      "; " + none_left);
    }
  }
  // 4. Published in order.
  for (auto* f : v) {
    auto& s = *f->s_;
    const char* from = f->temp_path_.c_str();
    const char* to = f->final_path_.c_str();
    int err = 0;
    if (f->overwrite_ == Overwrite::allow) {
      if (::rename(from, to) != 0) err = errno;
    } else if (::renameat2(AT_FDCWD, from, AT_FDCWD, to, RENAME_NOREPLACE) != 0) {
      err = errno;
      if (err == EINVAL || err == ENOSYS || err == ENOTSUP) {
        // No RENAME_NOREPLACE here (NFS, some FUSE filesystems): link(2)
        // fails with EEXIST just as atomically.
        err = ::link(from, to) == 0 ? 0 : errno;
        if (err == 0) ::unlink(from);
      }
    }
    if (err != 0) {
      roll_back();
      if (err == EEXIST) {
        throw Error(ErrorKind::io, "E_OUTPUT_EXISTS",
                    f->final_path_.string() + ": another process put a file at this path while this run was writing it "
                                              "(another run into the same folder?); it was left as it is and this run's "
                                              "output discarded: " + none_left);
      }
      throw Error(ErrorKind::io, "E_RENAME",
                  f->final_path_.string() + ": cannot move the finished output into place: " + reason(err) + "; " + none_left);
    }
    s.published = true;
  }
  for (auto* f : v) {
    f->committed_ = true;
    unregister_temp(f->registry_slot_);
    f->registry_slot_ = -1;
  }
  // 5. The renames on disk: each folder fsync'ed once.
  std::set<std::string> folders;
  for (auto* f : v) folders.insert(f->final_path_.has_parent_path() ? f->final_path_.parent_path().string() : ".");
  std::string sync_error;
  for (const auto& d : folders) {
    const int fd = ::open(d.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) {
      sync_error = d + ": " + reason(errno);
      continue;
    }
    if (::fsync(fd) != 0 && errno != EINVAL) sync_error = d + ": " + reason(errno);  // EINVAL: cannot sync folders there
    ::close(fd);
  }
  // The locks go only now: until here a sidecar published first is still
  // claimed by this process while its tile is being published.
  for (auto* f : v) {
    f->s_->buf.start_writeback_on(-1);
    if (f->s_->lock_fd >= 0) ::close(f->s_->lock_fd);
    f->s_->lock_fd = -1;
  }
  if (!sync_error.empty()) {
    throw Error(ErrorKind::io, "E_WRITE",
                names + ": published, but the folder could not be synced (" + sync_error +
                    "): the output may not survive a power cut");
  }
}

DataOutput::DataOutput(const std::string& path, Overwrite overwrite) {
  if (path.empty() || path == "-") return;
  data_ = std::make_unique<AtomicOutputFile>(path, overwrite);
  sidecar_ = std::make_unique<AtomicOutputFile>(path + ".geoanchor.json", overwrite);
}

DataOutput::~DataOutput() = default;

std::ostream& DataOutput::stream() { return data_ ? data_->stream() : std::cout; }

std::ostream& DataOutput::sidecar() {
  if (!sidecar_) throw std::logic_error("DataOutput::sidecar: standard output has no sidecar");
  return sidecar_->stream();
}

void DataOutput::commit(std::string_view what_for_standard_output) {
  if (!data_) {
    finish_standard_output(what_for_standard_output);
    return;
  }
  publish_together({sidecar_.get(), data_.get()});
}

void DataOutput::commit_with(const std::vector<AtomicOutputFile*>& others, std::string_view what_for_standard_output) {
  std::vector<AtomicOutputFile*> group = others;
  if (data_) {
    group.push_back(sidecar_.get());
    group.push_back(data_.get());
  } else {
    // Standard output first: if it fails, the others are still temporaries
    // (removed as they are destroyed), so none of the group is left.
    finish_standard_output(what_for_standard_output, others.empty() ? "" : "; no other output was written");
  }
  if (!group.empty()) publish_together(group);
}

void finish_standard_output(std::string_view what, std::string_view consequence) {
  errno = 0;
  std::cout.flush();
  bool ok = static_cast<bool>(std::cout);
  int err = errno;
  if (std::fflush(stdout) != 0) {
    ok = false;
    if (err == 0) err = errno;
  }
  if (std::ferror(stdout) != 0) ok = false;
  if (!ok) {
    throw Error(ErrorKind::io, "E_WRITE",
                "standard output: " + std::string(what) + " could not be written" +
                    (err != 0 ? " (" + reason(err) + ")" : std::string()) + std::string(consequence));
  }
}

}  // namespace geoanchor::io
