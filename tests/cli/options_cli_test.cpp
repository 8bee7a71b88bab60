// Every numeric command-line option of every subcommand refuses NaN and
// infinities (issue 12 point 6): CLI11's CLI::Range lets "nan" through, and
// `--max-extrapolation nan` used to switch the extrapolation refusal off,
// `--alpha nan` to end in an internal Boost error. Each flag is given `nan`,
// `inf` and `-inf` (as --flag=VALUE, so that "-inf" is not read as short
// options) and must be refused at parse time: exit 2, the flag, the value and
// the expected range in the message, nothing written.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

using testing::CliTest;
using testing::RunResult;

struct NumericOption {
  const char* name;      // test name
  const char* command;   // the command line before the flag (inputs need not exist: parsing fails first)
  const char* flag;
  const char* expected;  // what the message says is accepted
};

struct Case {
  NumericOption option;
  const char* value;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.option.name << "_" << c.value; }

const NumericOption kOptions[] = {
    {"convert_precision", "convert in.csv --to ecef", "--precision", "expected an integer in [0, 15]"},
    {"transform_precision", "transform in.csv --from ITRF2014@2010.0 --to ITRF2020", "--precision",
     "expected an integer in [0, 15]"},
    {"apply_resolution", "apply tile.csv --out-dir out", "--resolution", "expected a finite number in [1e-06, 10]"},
    {"apply_max_extrapolation", "apply tile.csv --out-dir out", "--max-extrapolation",
     "expected a finite number in [0, 1e+07]"},
    {"apply_jobs", "apply tile.csv --out-dir out", "--jobs", "expected an integer in [1, 32]"},
    {"convert_max_extrapolation", "convert in.csv --to enu --origin 47,8,400", "--max-extrapolation",
     "expected a finite number in [0, 1e+07]"},
    {"locate_max_extrapolation", "locate map points.csv", "--max-extrapolation", "expected a finite number in [0, 1e+07]"},
    {"fit_alpha", "fit control.csv --model helmert7 --convention position_vector", "--alpha",
     "expected a finite number in [1e-06, 0.5]"},
    {"fit_alpha_point", "fit control.csv --model helmert7 --convention position_vector", "--alpha-point",
     "expected a finite number in [1e-09, 0.5]"},
    {"diagnose_sigma", "diagnose control.csv", "--sigma", "expected a finite number > 0"},
#ifdef GEOANCHOR_GUI_EXE
    // The window: `geoanchor gui` hands its arguments to geoanchor-gui.
    {"gui_frames", "gui control.csv", "--frames", "expected an integer in [0, 2147483647]"},
#endif
};

std::vector<Case> all_cases() {
  std::vector<Case> out;
  for (const auto& o : kOptions) {
    for (const char* v : {"nan", "inf", "-inf"}) out.push_back({o, v});
  }
  return out;
}

class NumericOptionCli : public CliTest, public ::testing::WithParamInterface<Case> {};

// issue 12 point 6
TEST_P(NumericOptionCli, Issue12Point6_NonFiniteValueIsRefusedNamingTheFlagTheValueAndTheRange) {
  const Case c = GetParam();
  const std::string flag = c.option.flag, value = c.value;
  const RunResult r = run(std::string(c.option.command) + " " + flag + "=" + value);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  const std::string expected =
      "error[E_USAGE]: " + flag + ": value " + value + " is not a finite number; " + c.option.expected;
  EXPECT_NE(r.err.find(expected), std::string::npos) << "expected: " << expected << "\nstderr: " << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_TRUE(leftovers({}).empty()) << "left behind: " << ::testing::PrintToString(leftovers({}));
}

INSTANTIATE_TEST_SUITE_P(EveryNumericOption, NumericOptionCli, ::testing::ValuesIn(all_cases()),
                         [](const ::testing::TestParamInfo<Case>& p) {
                           std::string v = p.param.value;
                           if (v == "-inf") v = "minus_inf";
                           return std::string(p.param.option.name) + "_" + v;
                         });

class OptionsCli : public CliTest {};

// issue 12 point 6
TEST_F(OptionsCli, Issue12Point6_AFiniteValueOutsideTheRangeOrNotAnIntegerIsRefusedToo) {
  const RunResult frac = run("convert in.csv --to ecef --precision=2.5");
  EXPECT_EQ(frac.exit_code, 2) << frac.err;
  EXPECT_NE(frac.err.find("--precision: value 2.5 is not an integer; expected an integer in [0, 15]"), std::string::npos)
      << frac.err;
  const RunResult big = run("apply tile.csv --out-dir out --max-extrapolation=2e7");
  EXPECT_EQ(big.exit_code, 2) << big.err;
  EXPECT_NE(big.err.find("--max-extrapolation: value 2e7 is out of range; expected a finite number in [0, 1e+07]"),
            std::string::npos)
      << big.err;
  const RunResult zero = run("diagnose control.csv --sigma=0");
  EXPECT_EQ(zero.exit_code, 2) << zero.err;
  EXPECT_NE(zero.err.find("--sigma: value 0 is out of range; expected a finite number > 0"), std::string::npos)
      << zero.err;
  EXPECT_TRUE(leftovers({}).empty()) << "left behind: " << ::testing::PrintToString(leftovers({}));
}

// Issue 40 point 13: a mistyped command or option is named with the
// nearest that exists; nothing is run and nothing written.
TEST_F(OptionsCli, Issue40_UsageErrorsSuggestTheNearestCommandOrOption) {
  struct Typo {
    const char* command_line;
    const char* says;
  };
  const Typo typos[] = {
      {"conver in.csv --to ecef", "'conver' is not a command; did you mean 'convert'?"},
      {"tranform in.csv --from ITRF2014@2010.0 --to ITRF2020", "did you mean 'transform'?"},
      {"convert in.csv --to enu --orgin 47.46,8.55,480", "--orgin is not an option of convert: did you mean --origin?"},
      {"convert in.csv --to enu --orgin=47.46,8.55,480", "did you mean --origin?"},
      {"fit control.csv --model helmert7 --remove-outlier", "did you mean --remove-outliers?"},
      {"apply tile.csv --out-dir out --max-extrapolaton 5", "did you mean --max-extrapolation?"},
      {"help conver", "did you mean 'convert'?"},
      {"Convert in.csv --to ecef", "did you mean 'convert'?"},
      {"CONVERT in.csv --to ecef", "did you mean 'convert'?"},
      // One dash: CLI11 read "-overwrite" as "-o verwrite" and wrote a file named "verwrite".
      {"convert in.csv --to ecef -overwrite", "-overwrite: a long option takes two dashes: did you mean --overwrite?"},
      {"fit control.csv --model helmert7 -remove-outliers", "did you mean --remove-outliers?"},
      {"convert in.csv --to ecef -precision 3", "did you mean --precision?"},
  };
  for (const auto& t : typos) {
    const RunResult r = run(t.command_line);
    EXPECT_EQ(r.exit_code, 2) << t.command_line << ": " << r.err;
    EXPECT_NE(r.err.find(t.says), std::string::npos) << t.command_line << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  // Far from every name: no guess, the commands listed.
  const RunResult far = run("frobnicate in.csv");
  EXPECT_EQ(far.exit_code, 2);
  EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
  EXPECT_NE(far.err.find("(commands: convert, fit"), std::string::npos) << far.err;
  EXPECT_TRUE(leftovers({}).empty()) << "left behind: " << ::testing::PrintToString(leftovers({}));
}

// Issue 40 point 10: help, the version and crs print to standard output
// like every result; a full device is an error (exit 5), as for the others.
TEST_F(OptionsCli, Issue40_HelpVersionAndCrsFailWhenStandardOutputCannotBeWritten) {
  for (const std::string args : {"--version", "version", "--help", "help", "help fit", "convert --help", "crs EPSG:4326",
                                 "crs EPSG:4326 --json"}) {
    const RunResult r = shell("{ " + exe() + " " + args + " > /dev/full; }");
    EXPECT_EQ(r.exit_code, 5) << args << ": " << r.err;
    EXPECT_NE(r.err.find("E_WRITE"), std::string::npos) << args << ": " << r.err;
  }
  EXPECT_EQ(run("--version").exit_code, 0);
}

}  // namespace
}  // namespace geoanchor
