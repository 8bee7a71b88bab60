#pragma once
// What the subcommands share on the command line itself: the value parsers
// (geoanchor/workflow/value_text.hpp, also used by the window) and the
// CLI11 registration of options several subcommands take.

#include "geoanchor/workflow/value_text.hpp"

namespace CLI {
class App;
class Validator;
}

namespace geoanchor::cli {

using workflow::apply_control_grids;
using workflow::ControlGridOptions;
using workflow::parse_convention;
using workflow::parse_ellipsoid;
using workflow::parse_geoid;
using workflow::parse_model;
using workflow::parse_origin;
using workflow::parse_tm;
using workflow::parse_zone;
using workflow::split_numbers;

// Checks for every numeric command-line option (issue 12 point 6). CLI11's
// CLI::Range lets "nan" through (every comparison with NaN is false) and
// prints the largest double as the bound of CLI::PositiveNumber; these take
// the option's text, accept only a finite number (std::from_chars, no
// "nan"/"inf", no '+', no spaces) inside the stated range, and otherwise
// make CLI11 report `--flag: value nan is not a finite number; expected a
// number in [1e-06, 0.5]` (geoanchor: error[E_USAGE], exit 2).
CLI::Validator finite_range(double lo, double hi);          // [lo, hi]
CLI::Validator finite_positive();                           // > 0, finite
CLI::Validator integer_range(long long lo, long long hi);   // an integer in [lo, hi]

// The exit codes (ErrorKind, geoanchor/base/error.hpp), the footer of
// `geoanchor --help`, of every subcommand's --help and of geoanchor-gui's.
inline constexpr const char* kExitCodeHelp =
    "Exit codes:\n"
    "  0  success\n"
    "  2  usage: the command line is wrong (an unknown option, a bad flag value)\n"
    "  3  bad input: a file or value is invalid (named with file:line, field and value)\n"
    "  4  rejected: the computation ran but its result is refused (e.g. a failed global test); nothing is written\n"
    "  5  I/O: an input cannot be read, an output exists (without --overwrite) or cannot be written\n"
    "  1  internal error (a bug: please report it)\n"
    "Errors print as 'geoanchor: error[CODE]: message' on standard error.\n";

// --src-zone, --src-tm, --dst-zone, --dst-tm: the grids of a control set's
// easting/northing columns.
void add_control_grid_options(CLI::App& cmd, ControlGridOptions& o);

}  // namespace geoanchor::cli
