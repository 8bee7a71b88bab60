#include "geoanchor/io/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <csignal>
#include <cstring>
#include <random>

#include "geoanchor/geodesy/error.hpp"

namespace geoanchor::io {
namespace {

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

int register_temp(const std::filesystem::path& p) {
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

std::string random_suffix() {
  std::random_device rd;
  const auto v = (static_cast<unsigned long long>(rd()) << 32) ^ rd();
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", v);
  return buf;
}

}  // namespace

void install_signal_cleanup() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) std::signal(sig, cleanup_and_reraise);
}

void refuse_same_file(const std::filesystem::path& input, const std::filesystem::path& output) {
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(input, output, ec)) {
    throw Error(ErrorKind::usage, "E_OUTPUT_IS_INPUT",
                output.string() + ": the output would be the input file; the input is never modified, choose another "
                                  "output");
  }
}

AtomicOutputFile::AtomicOutputFile(std::filesystem::path final_path, Overwrite overwrite)
    : final_path_(std::move(final_path)) {
  std::error_code ec;
  if (overwrite == Overwrite::refuse && std::filesystem::exists(final_path_, ec)) {
    throw Error(ErrorKind::io, "E_OUTPUT_EXISTS",
                final_path_.string() + ": output already exists; pass --overwrite to replace it");
  }
  const auto dir = final_path_.has_parent_path() ? final_path_.parent_path() : std::filesystem::path(".");
  if (!std::filesystem::is_directory(dir, ec)) {
    throw Error(ErrorKind::io, "E_OUTPUT_DIR", final_path_.string() + ": folder " + dir.string() + " does not exist");
  }
  std::string temp_name = ".";
  temp_name.append(final_path_.filename().string()).append(".tmp-").append(random_suffix());
  temp_path_ = dir / temp_name;
  registry_slot_ = register_temp(temp_path_);
  out_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!out_) {
    unregister_temp(registry_slot_);
    throw Error(ErrorKind::io, "E_OUTPUT_OPEN",
                temp_path_.string() + ": cannot create temporary output: " + std::strerror(errno));
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
  }
  unregister_temp(registry_slot_);
}

void AtomicOutputFile::commit() {
  out_.flush();
  const bool write_ok = static_cast<bool>(out_);
  out_.close();
  bool sync_ok = false;
  if (write_ok) {
    const int fd = ::open(temp_path_.c_str(), O_RDONLY);
    if (fd >= 0) {
      sync_ok = ::fsync(fd) == 0;
      ::close(fd);
    }
  }
  std::error_code ec;
  if (!write_ok || !sync_ok) {
    std::filesystem::remove(temp_path_, ec);
    throw Error(ErrorKind::io, "E_WRITE",
                final_path_.string() + ": writing failed (disk full or I/O error); no output was left");
  }
  std::filesystem::rename(temp_path_, final_path_, ec);
  if (ec) {
    std::filesystem::remove(temp_path_, ec);
    throw Error(ErrorKind::io, "E_RENAME", final_path_.string() + ": cannot move the finished output into place: " +
                                               ec.message());
  }
  committed_ = true;
}

}  // namespace geoanchor::io
