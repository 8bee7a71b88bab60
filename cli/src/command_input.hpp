#pragma once
// The files a command names, as PROJ's and GDAL's tools take them: an input
// path, or "-" for standard input, opened once with the name messages use
// ("<stdin>" or the path); an output path, written atomically, or "-" for
// standard output; and a control set read from either (CSV or JSON by
// content). Command-line arguments must be UTF-8: they are recorded in the
// JSON outputs.

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/io/atomic_file.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/base/hash.hpp"

namespace geoanchor::cli {

// How an input path is named in reports and JSON: "<stdin>" for "-".
inline std::string input_name(const std::string& path) { return path == "-" ? "<stdin>" : path; }

// The same for a command's list of inputs.
inline std::vector<std::string> input_names(const std::vector<std::string>& paths) {
  std::vector<std::string> out;
  for (const auto& p : paths) out.push_back(input_name(p));
  return out;
}

class CommandInput {
 public:
  // Throws geoanchor::Error (io) naming the path when it cannot be opened.
  explicit CommandInput(const std::string& path) : from_stdin_(path == "-"), name_(input_name(path)) {
    if (from_stdin_) return;
    file_.open(path, std::ios::binary);
    if (!file_) throw Error(ErrorKind::io, "E_READ", path + ": cannot open input: " + std::strerror(errno));
  }

  std::istream& stream() { return from_stdin_ ? std::cin : file_; }
  const std::string& name() const { return name_; }
  bool from_stdin() const { return from_stdin_; }

 private:
  bool from_stdin_;
  std::string name_;
  std::ifstream file_;
};

// Writes the provenance sidecar, publishes it with the data (both written,
// then published: io::DataOutput), and with --json prints the same text on
// standard output, failing (E_WRITE) if it could not be.
inline void publish_with_provenance(io::DataOutput& output, const std::string& side_text, std::string_view rows, bool json,
                                    const std::string& path) {
  output.sidecar() << side_text;
  output.commit(rows);
  if (json) {
    std::cout << side_text;
    io::finish_standard_output("the provenance (--json)", "; " + path + " was written");
  }
}

// "-" (or no -o at all, where a command allows that): standard output.
inline bool is_standard_output(const std::string& path) { return path.empty() || path == "-"; }

// Where a command's main output goes: a file written to a temporary beside
// it and renamed by commit() (io::AtomicOutputFile: an existing file is
// refused unless `overwrite`), or standard output for "-" (or empty).
class CommandOutput {
 public:
  CommandOutput(const std::string& path, bool overwrite)
      : name_(is_standard_output(path) ? "<stdout>" : path) {
    if (!is_standard_output(path)) {
      file_ = std::make_unique<io::AtomicOutputFile>(path, overwrite ? io::Overwrite::allow : io::Overwrite::refuse);
    }
  }

  bool to_stdout() const { return !file_; }
  std::ostream& stream() { return file_ ? file_->stream() : std::cout; }
  const std::string& name() const { return name_; }  // "<stdout>" or the path

  // Publishes the file; on standard output, flushes it. Throws
  // geoanchor::Error (io, E_WRITE) when standard output could not be written.
  void commit() {
    if (file_) {
      file_->commit();
      return;
    }
    std::cout.flush();
    if (!std::cout) throw Error(ErrorKind::io, "E_WRITE", "<stdout>: write failed");
  }

 private:
  std::string name_;
  std::unique_ptr<io::AtomicOutputFile> file_;
};

// A control set as a command reads it: from the path, or from standard
// input for "-" (CSV or JSON, told apart by the first non-blank character
// as io::read_control_set does), with the name messages use and, when
// `hash` (reports; it costs a pass over the bytes), the SHA-256 of the
// bytes read.
struct ControlInput {
  geodesy::ControlSet set;
  std::string name;  // "<stdin>" or the path
  bool from_stdin = false;
  std::string sha256;  // empty unless asked for
  // fit --src/--dst: the two files, one frame each (role "source" or
  // "target", path, SHA-256 when asked for); `name` is "SRC + DST".
  struct RoleFile {
    std::string role, path, sha256;
  };
  std::vector<RoleFile> role_files;
  std::vector<std::string> notes;  // what the join of the two files left out
};

inline ControlInput read_control_input(const std::string& path, const io::ControlReadOptions& options, bool hash = false) {
  ControlInput c;
  c.from_stdin = path == "-";
  c.name = input_name(path);
  if (!c.from_stdin) {
    c.set = io::read_control_set(path, options);
    if (hash) c.sha256 = sha256_file_hex(path);
    return c;
  }
  // Standard input can be read once: kept in memory, hashed, then parsed.
  std::string text;
  char block[1 << 16];
  for (std::size_t n; (n = std::fread(block, 1, sizeof block, stdin)) > 0;) text.append(block, n);
  if (std::ferror(stdin)) throw Error(ErrorKind::io, "E_READ", "<stdin>: read error: " + std::string(std::strerror(errno)));
  if (hash) c.sha256 = sha256_hex(text);
  const auto first = text.find_first_not_of(" \t\r\n");
  const bool json = first != std::string::npos && text[first] == '{';
  std::istringstream in(std::move(text));
  c.set = json ? io::read_control_json(in, c.name, options) : io::read_control_csv(in, c.name, options);
  return c;
}

// A control set from two files, one frame each (io::read_control_pair).
inline ControlInput read_control_pair_input(const std::string& source, const std::string& target,
                                            const io::ControlReadOptions& options, bool unmatched_allowed, bool hash = false) {
  for (const auto* path : {&source, &target}) {
    if (*path == "-") {
      throw Error(ErrorKind::usage, "E_OPTION", "--src/--dst: give files (standard input holds one file; a control set with "
                                                "both frames' columns can come from it as CONTROL)");
    }
  }
  ControlInput c;
  c.set = io::read_control_pair(source, target, options, unmatched_allowed, &c.notes);
  c.name = c.set.source_name;
  c.role_files = {{"source", source, hash ? sha256_file_hex(source) : std::string()},
                  {"target", target, hash ? sha256_file_hex(target) : std::string()}};
  return c;
}

// Throws geoanchor::Error (input, E_ARGUMENT_NOT_UTF8) for the first
// command-line argument (argv[0] included) that is not UTF-8: geoanchor
// records its command line and the paths it reads and writes in JSON
// (sidecars, transform files, summaries), which holds UTF-8 text only, and
// does not record a name other than the file's.
inline void require_utf8_arguments(const std::vector<std::string>& argv) {
  for (std::size_t i = 0; i < argv.size(); ++i) {
    if (const auto problem = utf8_problem(argv[i])) {
      throw Error(ErrorKind::input, "E_ARGUMENT_NOT_UTF8",
                  std::string(i == 0 ? "the program's path" : "argument " + std::to_string(i)) + " '" + argv[i] +
                      "' is not valid UTF-8 (" + *problem +
                      "): geoanchor records its command line and the paths it reads and writes in JSON outputs, which "
                      "hold UTF-8 only, and records no name other than the file's; rename the file (from Latin-1: "
                      "convmv -f latin1 -t utf-8 --notest NAME), or give an input on standard input as -");
    }
  }
}

}  // namespace geoanchor::cli
