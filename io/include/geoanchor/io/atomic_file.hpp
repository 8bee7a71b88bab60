#pragma once
// Outputs appear whole or not at all, only where no other kind of file
// stands, and never over an output that another run published meanwhile.
//
// Where an output may go. The final path must be absent, a regular file or
// a symbolic link to a regular file. Anything else (a device, a FIFO, a
// socket, a folder, a dangling link, a link to any of those) is refused with
// or without --overwrite: E_OUTPUT_NOT_REGULAR, naming the path and what it
// is. An existing file is refused without --overwrite (E_OUTPUT_EXISTS).
// With --overwrite a symbolic link is replaced by the output itself: the
// file it pointed to is left as it was, so a link never makes geoanchor
// write outside the output's folder.
//
// How it is written. A temporary `.NAME.tmp-XXXXXXXXXXXXXXXX` (16 lowercase
// hexadecimal digits) is created beside the final path (O_EXCL) and held
// locked (flock) by its writer for as long as it exists; it is flushed and
// fsync'ed, then published by a rename, then its folder is fsync'ed. Without
// --overwrite the rename is renameat2(RENAME_NOREPLACE) (a hard link and an
// unlink where the filesystem lacks that flag, e.g. NFS), so an output that
// another process published between this one's check and its rename is
// never replaced: this one is discarded instead (E_OUTPUT_EXISTS). With
// --overwrite it is a plain rename(2), which replaces the file atomically,
// after checking again that the final path holds a regular file.
//
// Outputs that are one (a tile and its sidecar, a CSV and its sidecar) are
// published by publish_together(): all written and fsync'ed before the
// first is published.
//
// Cleaning up. On an exception the destructor removes the temporary; on
// SIGINT, SIGTERM, SIGHUP, SIGPIPE or SIGXFSZ the handler installed by
// install_signal_cleanup() removes every temporary still open. A process killed by SIGKILL (or a
// power cut) leaves its temporaries: the first output a later process opens
// in that folder removes the stale ones (remove_stale_temporaries()).

#include <chrono>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace geoanchor::io {

// What to do when the final path already holds a regular file.
enum class Overwrite { refuse, allow };

class AtomicOutputFile {
 public:
  // Throws geoanchor::Error (io): E_OUTPUT_NOT_REGULAR if the final path
  // holds anything but a regular file (or a link to one), E_OUTPUT_EXISTS if
  // it holds one and `overwrite` is refuse, E_OUTPUT_DIR if its folder does
  // not exist, E_OUTPUT_OPEN if the temporary cannot be created.
  AtomicOutputFile(std::filesystem::path final_path, Overwrite overwrite);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream();
  const std::filesystem::path& final_path() const { return final_path_; }
  const std::filesystem::path& temporary_path() const { return temp_path_; }

  // Flush, fsync, publish, fsync the folder: publish_together({this}).
  void commit();

 private:
  friend void publish_together(const std::vector<AtomicOutputFile*>& outputs);
  struct State;
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  Overwrite overwrite_;
  std::unique_ptr<State> s_;
  int registry_slot_ = -1;
  bool committed_ = false;
};

// Several outputs that are one, in the order they are published. Every one
// is written completely (flushed, closed, fsync'ed) before the first is
// published, so a failure to write any of them (disk full, ...) leaves none
// at its final path (E_WRITE, naming all). They are then published one after
// the other, and their folders fsync'ed. If one cannot be published (another
// run published it meanwhile: E_OUTPUT_EXISTS; something else stands there
// now: E_OUTPUT_NOT_REGULAR; E_RENAME), those this call published before it
// are removed again. With Overwrite::allow, the last output's existing file
// is removed before the first is published: whoever finds the last one at
// its final path finds the others, complete and of the same run, beside it
// (apply gives the sidecar first and the tile last). Throws std::logic_error
// if an output was already committed.
void publish_together(std::initializer_list<AtomicOutputFile*> outputs);
// The same for a group assembled at run time (a command's optional outputs).
void publish_together(const std::vector<AtomicOutputFile*>& outputs);

// The check AtomicOutputFile's constructor makes on its final path, for a
// command that wants to refuse before doing its work. Throws as it does
// (E_OUTPUT_NOT_REGULAR, E_OUTPUT_EXISTS).
void check_output_path(const std::filesystem::path& path, Overwrite overwrite);

// A temporary this long unmodified and held by no process is stale. The
// lock decides; the age only covers the instant between creating a
// temporary and locking it.
inline constexpr std::chrono::seconds kStaleTemporaryAge{10};

// True for names of the form `.NAME.tmp-XXXXXXXXXXXXXXXX` (16 lowercase
// hexadecimal digits, NAME not empty): AtomicOutputFile's temporaries.
bool is_temporary_name(std::string_view file_name);

// Removes the stale temporaries in `folder` and returns their paths: names
// for which is_temporary_name() holds, regular files (not links) owned by
// this user, not modified for kStaleTemporaryAge, and locked by no process
// (a live writer holds its flock; a killed one's is gone with it). Another
// running process's temporaries are never removed, nor is anything where
// the lock cannot be taken for another reason (a filesystem without locks).
// AtomicOutputFile calls it once per folder and process, before its first
// temporary there.
std::vector<std::filesystem::path> remove_stale_temporaries(const std::filesystem::path& folder);

// The stale temporaries AtomicOutputFile removed by itself (its once-per-
// folder call above) since the last call, each once; a command reports them
// with stale_temporary_warning() on stderr and in its output's metadata.
// (Those a caller removes by calling remove_stale_temporaries() itself are
// the caller's to report.)
std::vector<std::filesystem::path> take_removed_stale_temporaries();

// "PATH: removed, a temporary output left by a run that was killed".
std::string stale_temporary_warning(const std::filesystem::path& path);

// Removes `path` (not following a link) unless a process holds it locked:
// publish_together() holds each output it published until the whole group
// is published, so a sidecar found without its tile is either being
// published right now (held: left alone, false) or was left by a run killed
// between the two renames (removed, true). True also when nothing is there.
bool remove_unless_held(const std::filesystem::path& path);

// A command's data output: a file published together with its provenance
// sidecar `PATH.geoanchor.json` (the sidecar first, then the data), or
// standard output, without sidecar, when `path` is empty or "-". The one place
// that decides what an output path means.
class DataOutput {
 public:
  // Opens both files (and so refuses an existing or non-regular path) before
  // any row is read.
  DataOutput(const std::string& path, Overwrite overwrite);
  ~DataOutput();
  DataOutput(const DataOutput&) = delete;
  DataOutput& operator=(const DataOutput&) = delete;

  bool is_standard_output() const { return data_ == nullptr; }
  std::ostream& stream();
  // The sidecar's stream; throws std::logic_error for standard output.
  std::ostream& sidecar();
  // Publishes the file and its sidecar together (publish_together), or
  // flushes standard output (finish_standard_output); throws Error (io).
  void commit(std::string_view what_for_standard_output);
  // The same, published with `others` as one group (`others` first, the
  // sidecar, the file last): a command's outputs that belong together. To
  // standard output: flushed first, then `others` published, so that a
  // failed write to it leaves none of them (what was printed stays
  // printed).
  void commit_with(const std::vector<AtomicOutputFile*>& others, std::string_view what_for_standard_output);

 private:
  std::unique_ptr<AtomicOutputFile> sidecar_, data_;
};

// Flushes standard output and throws geoanchor::Error (io, E_WRITE) if
// anything written to it was lost (a full disk, a closed descriptor):
// "standard output: WHAT could not be written (REASON)CONSEQUENCE".
void finish_standard_output(std::string_view what, std::string_view consequence = {});

// Installs handlers for SIGINT, SIGTERM and SIGHUP (and SIGPIPE and
// SIGXFSZ unless they are ignored) that unlink open temporaries and then
// re-raise the signal with its default action.
void install_signal_cleanup();

// Throws geoanchor::Error (usage) if `output` names the same file as `input`.
void refuse_same_file(const std::filesystem::path& input, const std::filesystem::path& output);

}  // namespace geoanchor::io
