#include "usage_hints.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <functional>

namespace geoanchor::cli {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

// Optimal string alignment distance (Damerau–Levenshtein without repeated edits of a substring).
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1, 0));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* sub : app.get_subcommands(std::function<bool(const CLI::App*)>())) names.push_back(sub->get_name());
  return names;
}

// The long options of `app` ("--origin"), and its flags', with the help flag.
std::vector<std::string> long_options(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* o : app.get_options()) {
    for (const auto& l : o->get_lnames()) names.push_back("--" + l);
  }
  return names;
}

std::string joined(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

}  // namespace

std::string nearest_name(std::string_view word, const std::vector<std::string>& candidates) {
  const std::string w = lower(word);
  std::string best;
  std::size_t best_distance = 0;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(w, lower(c));
    if (best.empty() || d < best_distance) best = c, best_distance = d;
  }
  // Leading dashes are not letters of the name.
  const std::size_t letters = w.size() - std::min(w.find_first_not_of('-'), w.size());
  const std::size_t allowed = std::max<std::size_t>(1, letters / 3);
  // The same letters in another case ("Convert") are a typo too.
  return !best.empty() && (best_distance > 0 || best != word) && best_distance <= allowed ? best : std::string();
}

std::string single_dash_long_option(const CLI::App& app, const std::vector<std::string>& args) {
  std::vector<std::string> names = long_options(app);
  for (const CLI::App* sub : app.get_subcommands(std::function<bool(const CLI::App*)>())) {
    const auto more = long_options(*sub);
    names.insert(names.end(), more.begin(), more.end());
  }
  for (const auto& a : args) {
    if (a == "--") break;  // what follows is not options
    if (a.size() < 3 || a[0] != '-' || a[1] == '-' || !std::isalpha(static_cast<unsigned char>(a[1])) ||
        !std::isalpha(static_cast<unsigned char>(a[2]))) {
      continue;
    }
    const std::string word = "-" + a.substr(0, a.find('='));  // "-overwrite" read as "--overwrite"
    const bool exact = std::find(names.begin(), names.end(), word) != names.end();
    const std::string near = exact ? word : nearest_name(word, names);
    if (near.empty()) continue;
    // CLI11 would read "-overwrite" as "-o verwrite" (an output file named
    // "verwrite"): a long option takes two dashes.
    return a + ": a long option takes two dashes: did you mean " + near + "?";
  }
  return "";
}

std::string usage_hint(const CLI::App& app, const std::vector<std::string>& args, const std::string& what) {
  // Which command was chosen, if any.
  const CLI::App* chosen = nullptr;
  for (const CLI::App* sub : app.get_subcommands(std::function<bool(const CLI::App*)>())) {
    if (sub->parsed()) chosen = sub;
  }
  if (!chosen) {
    // The first word that is not an option is the command.
    const auto word = std::find_if(args.begin(), args.end(), [](const std::string& a) { return a.empty() || a[0] != '-'; });
    if (word == args.end()) return what;
    const auto names = subcommand_names(app);
    const std::string near = nearest_name(*word, names);
    return "'" + *word + "' is not a command" + (near.empty() ? "" : "; did you mean '" + near + "'?") + " (commands: " +
           joined(names) + ")";
  }
  // Options the command does not have, each with the nearest it has.
  std::vector<std::string> unknown;
  const auto known = long_options(*chosen);
  const auto app_known = long_options(app);
  std::string hints;
  for (const auto& a : args) {
    if (a.size() < 3 || a.compare(0, 2, "--") != 0) continue;
    const std::string name = a.substr(0, a.find('='));
    if (std::find(known.begin(), known.end(), name) != known.end() ||
        std::find(app_known.begin(), app_known.end(), name) != app_known.end()) {
      continue;
    }
    const std::string near = nearest_name(name, known);
    hints += (hints.empty() ? "" : "; ") + name + " is not an option of " + chosen->get_name() +
             (near.empty() ? "" : ": did you mean " + near + "?");
  }
  return hints.empty() ? what : hints + " (" + what + ")";
}

std::string help_command(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands(std::function<bool(const CLI::App*)>())) {
    if (sub->parsed()) return "geoanchor " + sub->get_name() + " --help";
  }
  return "geoanchor --help";
}

}  // namespace geoanchor::cli
