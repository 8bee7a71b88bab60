// Every example command in README.md and docs/**/*.md runs as written
// (issue 12 point 15: two documented examples used files that were not
// shipped). The ```sh blocks of each page are run in order in one folder per
// page, with the repository's fixtures/ there and `geoanchor` on the PATH:
//
// - in a block with `$ ` prompts, the prompted lines are the commands (the
//   other lines are their output); in a block without, every line that is
//   not blank or a comment is one;
// - a line ending in `\` continues on the next;
// - a command must exit 0, or N where it ends in a `# exits N` comment;
// - a command with a `# not run` comment is skipped (the window of
//   `geoanchor gui`, scheduler scripts): the test counts them, and each must
//   say why after `# not run:`.
//
// GEOANCHOR_DOCS_ROOT (a folder with README.md, docs/ and fixtures/) runs
// another tree's pages, e.g. the base commit's, to show what failed there.

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::RunResult;
using testing::slurp;

struct Example {
  std::string page;  // relative to the root
  int line = 0;      // 1-based, of the command's first line
  std::string command;
  int expected_exit = 0;
  bool run = true;
};

fs::path docs_root() {
  const char* other = std::getenv("GEOANCHOR_DOCS_ROOT");
  return other && *other ? fs::path(other) : fs::path(GEOANCHOR_SOURCE_DIR);
}

std::vector<std::string> pages(const fs::path& root) {
  std::vector<std::string> out{"README.md"};
  for (const auto& e : fs::recursive_directory_iterator(root / "docs")) {
    if (e.is_regular_file() && e.path().extension() == ".md") out.push_back(fs::relative(e.path(), root).string());
  }
  std::sort(out.begin() + 1, out.end());
  return out;
}

// The commands of the ```sh blocks of one page, in order.
std::vector<Example> examples(const fs::path& root, const std::string& page) {
  std::vector<std::string> lines;
  {
    std::istringstream in(slurp(root / page));
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  std::vector<Example> out;
  static const std::regex kExits(R"(#\s*exits\s+([0-9]+)\s*$)");
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i] != "```sh") continue;
    std::size_t end = i + 1;
    while (end < lines.size() && !lines[end].starts_with("```")) ++end;
    const bool prompts = std::any_of(lines.begin() + static_cast<long>(i) + 1, lines.begin() + static_cast<long>(end),
                                     [](const std::string& l) { return l.starts_with("$ "); });
    for (std::size_t k = i + 1; k < end; ++k) {
      std::string text = lines[k];
      if (prompts) {
        if (!text.starts_with("$ ")) continue;
        text.erase(0, 2);
      } else if (text.empty() || text.starts_with("#")) {
        continue;
      }
      Example e{page, static_cast<int>(k + 1), "", 0, true};
      while (text.ends_with("\\") && k + 1 < end) {
        text.pop_back();
        text += " " + lines[++k];
      }
      e.command = text;
      std::smatch m;
      if (std::regex_search(text, m, kExits)) e.expected_exit = std::stoi(m[1].str());
      if (text.find("# not run") != std::string::npos) e.run = false;
      out.push_back(e);
    }
    i = end;
  }
  return out;
}

// One test per page (so that CTest runs pages side by side: the pages
// that render PNGs take a few seconds each).
class DocsExamples : public CliTest, public ::testing::WithParamInterface<std::string> {};

// issue 12 point 15
TEST_P(DocsExamples, Point15_EveryDocumentedExampleRunsAsWritten) {
  const fs::path root = docs_root();
  const std::string page = GetParam();
  // `geoanchor` on the PATH is the executable under test.
  fs::create_directories(path("bin"));
  fs::create_symlink(fs::absolute(exe()), path("bin") / "geoanchor");
  // The page's examples build on each other (fit -o T.json, then apply --transform T.json).
  const fs::path folder = path("page");
  fs::create_directories(folder);
  fs::create_directory_symlink(root / "fixtures", folder / "fixtures");
  for (const Example& e : examples(root, page)) {
    if (!e.run) {
      EXPECT_NE(e.command.find("# not run:"), std::string::npos)
          << e.page << ":" << e.line << ": a skipped example says why after '# not run:': " << e.command;
      continue;
    }
    const RunResult r = shell("cd '" + folder.string() + "' && env -u DISPLAY -u WAYLAND_DISPLAY PATH='" +
                              path("bin").string() + ":'\"$PATH\" sh -c '" +
                              std::regex_replace(e.command, std::regex("'"), "'\\''") + "'");
    EXPECT_EQ(r.exit_code, e.expected_exit)
        << e.page << ":" << e.line << ": " << e.command << "\nstdout:\n" << r.out.substr(0, 2000) << "\nstderr:\n" << r.err;
  }
}

std::vector<std::string> pages_with_examples() {
  std::vector<std::string> out;
  for (const std::string& page : pages(docs_root())) {
    if (!examples(docs_root(), page).empty()) out.push_back(page);
  }
  return out;
}

INSTANTIATE_TEST_SUITE_P(Pages, DocsExamples, ::testing::ValuesIn(pages_with_examples()),
                         [](const ::testing::TestParamInfo<std::string>& param) {
                           std::string name = param.param;
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

// issue 12 point 15
TEST(DocsExamplesFound, Point15_ThePagesHoldTheirExamplesAndSkipFew) {
  std::size_t commands = 0, skipped = 0;
  bool saw_convert = false;
  for (const std::string& page : pages(docs_root())) {
    for (const Example& e : examples(docs_root(), page)) {
      ++commands;
      if (!e.run) ++skipped;
      if (page == "docs/commands/convert.md" && e.command.find("itrf2008_to_gda94.json") != std::string::npos) saw_convert = true;
    }
  }
  // README, apply, convert, fit, report, snapshot and transform hold 35 commands (2026-12);
  // the window, two build scripts and a scheduler's script are not run.
  EXPECT_GE(commands, 30u);
  EXPECT_LE(skipped, 4u);
  EXPECT_TRUE(saw_convert) << "the 14-parameter example of convert.md was not found";
}

}  // namespace
}  // namespace geoanchor
