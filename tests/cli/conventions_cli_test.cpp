// Issue 12 point 12 (CSV input edges: CR-only line ends, text that is not
// UTF-8) and point 15 (the command-line conventions users bring from PROJ
// and GDAL: `-` for standard input and output, --json, exit codes in
// --help, `help` and `version`, a tab- or ';'-separated file named as such).

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "cli_support.hpp"

namespace geoanchor {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CliTest;
using testing::RunResult;
using testing::slurp;

const std::string kControl = std::string(GEOANCHOR_FIXTURES_DIR) + "/airport_control.csv";
const std::string kNoDisplay = "env -u DISPLAY -u WAYLAND_DISPLAY ";
const std::string kFit = " --model helmert7 --convention position_vector";

// Three marks around LSZH in WGS 84, with a comment line.
const std::string kPointsLf =
    "# marks\n"
    "id,lat_deg,lon_deg,h_m\n"
    "THR16,47.476,8.536,480.2\n"
    "THR28,47.459,8.571,432.5\n"
    "ARP,47.464722,8.549167,480\n";

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = 0; (at = text.find(from, at)) != std::string::npos; at += to.size()) text.replace(at, from.size(), to);
  return text;
}

class Conventions : public CliTest {};

// ---- point 12: CR-only and mixed line ends read as the LF file ----

// issue 12 point 12
TEST_F(Conventions, Point12_CrOnlyAndMixedLineEndsConvertAsTheLfFile) {
  write("lf.csv", kPointsLf);
  write("cr.csv", replace_all(kPointsLf, "\n", "\r"));
  // CRLF, CR and LF in one file.
  write("mixed.csv", "# marks\r\nid,lat_deg,lon_deg,h_m\rTHR16,47.476,8.536,480.2\nTHR28,47.459,8.571,432.5\r\n"
                     "ARP,47.464722,8.549167,480\r");
  const RunResult lf = run("convert " + path("lf.csv").string() + " --to ecef");
  ASSERT_EQ(lf.exit_code, 0) << lf.err;
  ASSERT_NE(lf.out.find("ARP,"), std::string::npos) << lf.out;  // the LF file itself reads its three rows
  for (const char* name : {"cr.csv", "mixed.csv"}) {
    const RunResult r = run("convert " + path(name).string() + " --to ecef");
    ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
    EXPECT_EQ(r.out, lf.out) << name;
  }
}

// issue 12 point 12
TEST_F(Conventions, Point12_CrOnlyControlSetFitsAsTheLfFile) {
  write("cr.csv", replace_all(slurp(kControl), "\n", "\r"));
  const RunResult lf = run("fit " + kControl + " --remove-outliers" + kFit + " -o " + path("lf.json").string());
  ASSERT_EQ(lf.exit_code, 0) << lf.err;
  const RunResult cr = run("fit " + path("cr.csv").string() + " --remove-outliers" + kFit + " -o " + path("cr.json").string());
  ASSERT_EQ(cr.exit_code, 0) << cr.err;
  const json a = json::parse(slurp(path("lf.json"))), b = json::parse(slurp(path("cr.json")));
  for (const char* key : {"parameters", "sigmas", "statistics", "points"}) EXPECT_EQ(a.at(key), b.at(key)) << key;
  EXPECT_EQ(a.at("points").size(), 36u);  // the 36 marks of the bundled set
}

// ---- point 12: text that is not UTF-8 is refused where it is read ----

// issue 12 point 12
TEST_F(Conventions, Point12_Latin1IdInControlCsvIsRefusedNamingLineAndByte) {
  std::string text = slurp(kControl);
  // The first data row's id becomes Latin-1 "Pé".
  const std::size_t header = text.find("\nid,");
  ASSERT_NE(header, std::string::npos);
  const std::size_t row = text.find('\n', header + 1) + 1;
  text.replace(row, text.find(',', row) - row, "P\xE9");
  std::size_t line = 1;
  for (std::size_t i = 0; i < row; ++i) if (text[i] == '\n') ++line;
  write("latin1.csv", text);
  const RunResult r = run("fit " + path("latin1.csv").string() + kFit + " -o " + path("t.json").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("E_CSV_NOT_UTF8"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("latin1.csv:" + std::to_string(line) + ": id 'P\\xE9' is not valid UTF-8"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0xE9"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("E_INTERNAL"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"latin1.csv"}), std::vector<std::string>{});
}

// issue 12 point 12
TEST_F(Conventions, Point12_Latin1IdInControlJsonIsRefusedNotInternal) {
  write("latin1.json", "{\"points\": [{\"id\": \"P\xE9\"}]}\n");
  const RunResult r = run("fit " + path("latin1.json").string() + kFit + " -o " + path("t.json").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("latin1.json"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("UTF-8"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("E_INTERNAL"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"latin1.json"}), std::vector<std::string>{});
}

// issue 12 point 12
TEST_F(Conventions, Point12_Latin1FileNameIsRefusedNotInternal) {
  // The name is recorded in the sidecar (JSON); it used to end in E_INTERNAL there.
  write("in\xE9.csv", kPointsLf);
  const RunResult r = run("convert " + path("in\xE9.csv").string() + " --to ecef -o out.csv");
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("E_ARGUMENT_NOT_UTF8"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("in\\xE9.csv' is not valid UTF-8"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("E_INTERNAL"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"in\xE9.csv"}), std::vector<std::string>{});
  // The same bytes on standard input are read (they name no file).
  const RunResult piped = run("convert - --to ecef -o " + path("out.csv").string(), path("in\xE9.csv").string());
  EXPECT_EQ(piped.exit_code, 0) << piped.err;
}

// issue 12 point 12
TEST_F(Conventions, Point12_Latin1TileNameInAFolderIsRefusedNotInternal) {
  fs::create_directories(path("tiles"));
  write("tiles/t\xE9.csv", "x_m,y_m,z_m\n4271315.696,641096.356,4678048.542\n");
  const RunResult r = run("apply " + path("tiles").string() + " --to geodetic --out-dir " + path("out").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("E_PATH_NOT_UTF8"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("t\\xE9.csv"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("E_INTERNAL"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(path("out")));
}

// issue 12 point 12
TEST_F(Conventions, Point12_Latin1AttributeInACsvTileFailsThatTileAndTheSummaryNamesIt) {
  write("in/t.csv", "x_m,y_m,z_m,name\n4271315.696,641096.356,4678048.542,P\xE9\n");
  const RunResult r = run("apply " + path("in/t.csv").string() + " --from-frame ITRF2014@2024.5 --to geodetic --out-dir " +
                          path("out").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("t.csv:2: name 'P\\xE9' is not valid UTF-8"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("E_INTERNAL"), std::string::npos) << r.err;
  // No tile is written; the run summary (JSON, so UTF-8) holds the message
  // with the byte as \xE9: the latest run's and this run's own copy.
  const std::vector<std::string> left = files(path("out"));
  ASSERT_EQ(left.size(), 2u);
  EXPECT_EQ(left[0].rfind("geoanchor-apply-summary.", 0), 0u) << left[0];
  EXPECT_EQ(left[1], "geoanchor-apply-summary.json");
  const std::string summary = slurp(path("out") / "geoanchor-apply-summary.json");
  EXPECT_TRUE(json::accept(summary)) << summary;
  EXPECT_NE(summary.find("E_CSV_NOT_UTF8"), std::string::npos) << summary;
}

// ---- point 15: `-` is standard input and standard output ----

// issue 12 point 15
TEST_F(Conventions, Point15_DashOutputWritesStandardOutput) {
  write("in.csv", kPointsLf);
  const RunResult to_file = run("convert " + path("in.csv").string() + " --to ecef");
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  for (const char* command : {"convert", "transform"}) {
    const std::string args = std::string(command) == "convert" ? " --to ecef" : " --from ITRF2014@2024.5 --to ITRF2020@2024.5";
    const RunResult r = shell("cd '" + path("").string() + "' && " + exe() + " " + command + " in.csv" + args + " -o -");
    ASSERT_EQ(r.exit_code, 0) << command << ": " << r.err;
    EXPECT_NE(r.out.find("THR16,"), std::string::npos) << command << ": " << r.out;
    if (std::string(command) == "convert") {
      EXPECT_EQ(r.out, to_file.out);
    }
    EXPECT_EQ(leftovers({"in.csv"}), std::vector<std::string>{}) << command << ": no file '-', no sidecar";
  }
  // fit: the transform file on standard output, the report on standard error.
  const RunResult fit = shell("cd '" + path("").string() + "' && " + exe() + " fit " + kControl + " --remove-outliers" + kFit + " -o -");
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_EQ(json::parse(fit.out).at("model"), "helmert7");
  EXPECT_NE(fit.err.find("geoanchor fit: model helmert7"), std::string::npos) << fit.err;
  // snapshot: the PNG on standard output.
  const RunResult png = shell("cd '" + path("").string() + "' && " + kNoDisplay + exe() +
                              " snapshot " + kControl + " --view plan --size 1280x800 -o -");
  ASSERT_EQ(png.exit_code, 0) << png.err;
  EXPECT_EQ(png.out.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(leftovers({"in.csv"}), std::vector<std::string>{});
}

// issue 12 point 15
TEST_F(Conventions, Point15_DashForAFolderIsRefusedNotCreated) {
  const RunResult fit = run("fit " + kControl + " --remove-outliers" + kFit + " -o " + path("t.json").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  // report and apply write folders: `-` there would be a folder named '-'.
  const RunResult report = shell("cd '" + path("").string() + "' && " + kNoDisplay + exe() + " report " + kControl +
                                 " --transform t.json -o -");
  EXPECT_EQ(report.exit_code, 2) << report.err;
  EXPECT_NE(report.err.find("-o -: report writes a folder"), std::string::npos) << report.err;
  const RunResult apply = shell("cd '" + path("").string() + "' && " + exe() + " apply " + std::string(GEOANCHOR_FIXTURES_DIR) +
                                "/airport_tile.las --to ecef --out-dir -");
  EXPECT_EQ(apply.exit_code, 2) << apply.err;
  EXPECT_NE(apply.err.find("--out-dir -: apply writes each tile"), std::string::npos) << apply.err;
  EXPECT_EQ(leftovers({"t.json"}), std::vector<std::string>{});
}

// issue 12 point 15
TEST_F(Conventions, Point15_FitDiagnoseSnapshotReadTheControlSetFromStandardInput) {
  const RunResult file = run("fit " + kControl + " --remove-outliers" + kFit + " -o " + path("file.json").string());
  ASSERT_EQ(file.exit_code, 0) << file.err;
  const RunResult fit = run("fit - --remove-outliers" + kFit + " -o " + path("stdin.json").string(), kControl);
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_EQ(json::parse(slurp(path("file.json"))).at("parameters"), json::parse(slurp(path("stdin.json"))).at("parameters"));

  const RunResult diagnose = run("diagnose - --json", kControl);
  ASSERT_EQ(diagnose.exit_code, 0) << diagnose.err;
  EXPECT_EQ(json::parse(diagnose.out).at("schema"), "geoanchor.diagnosis/1");

  const RunResult snapshot = shell(kNoDisplay + exe() + " snapshot - --view plan --size 1280x800 -o " + path("p.png").string(), kControl);
  ASSERT_EQ(snapshot.exit_code, 0) << snapshot.err;
  EXPECT_TRUE(fs::exists(path("p.png")));
}

// ---- point 15: --json on every command that reports ----

// issue 12 point 15
TEST_F(Conventions, Point15_JsonOnEveryReportingCommand) {
  const RunResult fit = run("fit " + kControl + " --remove-outliers" + kFit + " --json -o " + path("t.json").string());
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  const json report = json::parse(fit.out);
  EXPECT_EQ(report.at("schema"), "geoanchor.fit-report/1");
  EXPECT_EQ(report.at("status"), "written");
  EXPECT_EQ(report.at("transform"), json::parse(slurp(path("t.json"))));

  const RunResult compare = run("fit " + kControl + " --compare --convention position_vector --json");
  ASSERT_EQ(compare.exit_code, 0) << compare.err;
  EXPECT_EQ(json::parse(compare.out).at("schema"), "geoanchor.fit-comparison/1");

  write("in.csv", kPointsLf);
  const RunResult convert = run("convert " + path("in.csv").string() + " --to ecef --json -o " + path("out.csv").string());
  ASSERT_EQ(convert.exit_code, 0) << convert.err;
  EXPECT_EQ(json::parse(convert.out), json::parse(slurp(path("out.csv.geoanchor.json"))));
  EXPECT_EQ(json::parse(convert.out).at("schema"), "geoanchor.convert-provenance/1");

  const RunResult transform = run("transform " + path("in.csv").string() +
                                  " --from ITRF2014@2024.5 --to ITRF2020@2024.5 --json -o " + path("moved.csv").string());
  ASSERT_EQ(transform.exit_code, 0) << transform.err;
  EXPECT_EQ(json::parse(transform.out).at("schema"), "geoanchor.transform-provenance/1");

  const RunResult snapshot =
      shell(kNoDisplay + exe() + " snapshot " + kControl + " --view plan --size 1280x800 --json -o " + path("p.png").string());
  ASSERT_EQ(snapshot.exit_code, 0) << snapshot.err;
  const json shot = json::parse(snapshot.out);
  EXPECT_EQ(shot.at("schema"), "geoanchor.snapshot/1");
  EXPECT_EQ(shot.at("bytes"), fs::file_size(path("p.png")));

  const RunResult rep = shell(kNoDisplay + exe() + " report " + kControl + " --transform " + path("t.json").string() +
                              " --size 1280x800 --json -o " + path("rep").string());
  ASSERT_EQ(rep.exit_code, 0) << rep.err;
  const json pages = json::parse(rep.out);
  EXPECT_EQ(pages.at("schema"), "geoanchor.report/1");
  for (const auto& f : pages.at("files")) {
    EXPECT_EQ(f.at("bytes"), fs::file_size(path("rep") / f.at("name").get<std::string>())) << f;
  }
}

// ---- point 15: exit codes in every --help; help and version ----

// issue 12 point 15
TEST_F(Conventions, Point15_EveryHelpListsTheExitCodes) {
  for (const char* command : {"", "convert", "transform", "fit", "apply", "diagnose", "snapshot", "report", "gui"}) {
    const RunResult r = run(std::string(command) + " --help");
    EXPECT_EQ(r.exit_code, 0) << command << ": " << r.err;
    EXPECT_NE(r.out.find("Exit codes:"), std::string::npos) << command << ": " << r.out;
    for (const char* line : {"  0  success", "  2  usage", "  3  bad input", "  4  rejected", "  5  I/O"}) {
      EXPECT_NE(r.out.find(line), std::string::npos) << command << ": " << line;
    }
  }
}

// issue 12 point 15
TEST_F(Conventions, Point15_VersionAndHelpAnswerAsUsersExpect) {
  for (const char* words : {"--version", "version"}) {
    const RunResult r = run(words);
    EXPECT_EQ(r.exit_code, 0) << words << ": " << r.err;
    EXPECT_TRUE(std::regex_match(r.out, std::regex("geoanchor [0-9]+\\.[0-9]+\\.[0-9]+\n"))) << words << ": " << r.out;
  }
  const RunResult help = run("help");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_EQ(help.out, run("--help").out);
  const RunResult help_fit = run("help fit");
  EXPECT_EQ(help_fit.exit_code, 0) << help_fit.err;
  EXPECT_EQ(help_fit.out, run("fit --help").out);
  const RunResult unknown = run("help nosuch");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("help nosuch: no such command; expected one of convert"), std::string::npos) << unknown.err;
}

// ---- point 15: a tab- or ';'-separated file is named as such ----

// issue 12 point 15
TEST_F(Conventions, Point15_TabSeparatedFileSaysTabs) {
  write("in.tsv", "id\tlat_deg\tlon_deg\th_m\nTHR16\t47.476\t8.536\t480.2\n");
  const RunResult r = run("convert " + path("in.tsv").string() + " --to ecef -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("in.tsv:1: the header is separated by tabs, not commas"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"in.tsv"}), std::vector<std::string>{});
}

// issue 12 point 15
TEST_F(Conventions, Point15_SemicolonSeparatedFileSaysSemicolons) {
  write("in.csv", "id;lat_deg;lon_deg;h_m\nTHR16;47,476;8,536;480,2\n");
  const RunResult r = run("convert " + path("in.csv").string() + " --to ecef -o " + path("out.csv").string());
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("in.csv:1: the header is separated by semicolons (';'), not commas"), std::string::npos) << r.err;
  EXPECT_EQ(leftovers({"in.csv"}), std::vector<std::string>{});
  // A control set too.
  write("control.csv", "id;x_src_m;y_src_m;z_src_m;x_dst_m;y_dst_m;z_dst_m\n");
  const RunResult fit = run("fit " + path("control.csv").string() + kFit);
  EXPECT_EQ(fit.exit_code, 3) << fit.err;
  EXPECT_NE(fit.err.find("separated by semicolons"), std::string::npos) << fit.err;
}

}  // namespace
}  // namespace geoanchor
