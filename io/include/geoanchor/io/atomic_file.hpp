#pragma once
// Outputs appear whole or not at all: written to a temporary file in the
// destination's folder, flushed and fsync'ed, then renamed over the final
// path. On an exception the destructor removes the temporary; on SIGINT,
// SIGTERM or SIGHUP the handler installed by install_signal_cleanup()
// removes every temporary still open.

#include <filesystem>
#include <fstream>
#include <string>

namespace geoanchor::io {

// What to do when the final path already exists.
enum class Overwrite { refuse, allow };

class AtomicOutputFile {
 public:
  // Throws geoanchor::Error (io) if the final path exists and `overwrite` is
  // refuse, or the temporary cannot be created.
  AtomicOutputFile(std::filesystem::path final_path, Overwrite overwrite);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream() { return out_; }
  const std::filesystem::path& final_path() const { return final_path_; }

  // Flush, fsync, rename. Throws geoanchor::Error (io) on failure (disk
  // full, ...), after removing the temporary.
  void commit();

 private:
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  std::ofstream out_;
  int registry_slot_ = -1;
  bool committed_ = false;
};

// Installs handlers for SIGINT, SIGTERM and SIGHUP that unlink open
// temporaries and then re-raise the signal with its default action.
void install_signal_cleanup();

// Throws geoanchor::Error (usage) if `output` names the same file as `input`.
void refuse_same_file(const std::filesystem::path& input, const std::filesystem::path& output);

}  // namespace geoanchor::io
