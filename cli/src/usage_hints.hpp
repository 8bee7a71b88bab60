#pragma once
// Usage errors that help (issue 40 point 13): a mistyped command or option
// is named with the nearest one that exists ("did you mean --origin?").

#include <string>
#include <string_view>
#include <vector>

namespace CLI {
class App;
}

namespace geoanchor::cli {

// The candidate nearest to `word` by edit distance (insertions, deletions,
// substitutions and swaps of neighbours, case-insensitive), when it is near
// enough to be a typo of it (at most a third of its letters, at least one);
// "" otherwise.
std::string nearest_name(std::string_view word, const std::vector<std::string>& candidates);

// The message for a command line CLI11 refused (its own text in `what`):
// an unknown command or options named with the nearest that exist, else
// `what` unchanged. `args` are the words after the program's name.
std::string usage_hint(const CLI::App& app, const std::vector<std::string>& args, const std::string& what);

// A word with one dash that reads as a long option ("-overwrite", which
// CLI11 takes as "-o verwrite"): the message naming it and the option meant,
// or "" when there is none. Checked before the command line is parsed.
std::string single_dash_long_option(const CLI::App& app, const std::vector<std::string>& args);

// "geoanchor convert --help" when a command was chosen, else "geoanchor --help".
std::string help_command(const CLI::App& app);

}  // namespace geoanchor::cli
