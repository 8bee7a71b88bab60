// SINEX station solutions read as one GNSS point cluster: the station
// positions of SOLUTION/ESTIMATE (STAX, STAY, STAZ) with their joint
// covariance from SOLUTION/MATRIX_ESTIMATE.
//
// The format as the SINEX 2.02 description (IERS/IGS, "SINEX - Solution
// (Software/technique) INdependent EXchange Format Version 2.02", 2006)
// defines it (docs/network-format.md lists what is read and how):
//  - a header line "%=SNX 2.02 AAA YY:DDD:SSSSS ... C ..." and "%ENDSNX";
//    blocks "+NAME" … "-NAME"; "*" comment lines;
//  - SOLUTION/ESTIMATE: INDEX TYPE CODE PT SOLN REF_EPOCH UNIT S VALUE
//    STD_DEV in fixed columns (2-6, 8-13, 15-18, 20-21, 23-26, 28-39,
//    41-44, 46, 48-68, 70-80); epochs YY:DDD:SSSSS;
//  - SOLUTION/MATRIX_ESTIMATE {L|U} {COVA|CORR|INFO}: PARA1 PARA2 and up to
//    three values of row PARA1 from column PARA2 on; CORR holds standard
//    deviations on its diagonal and correlations off it; INFO is the
//    normal matrix (its inverse is the covariance).
// The positions' covariance is the marginal one: other parameters
// (velocities, …) are left out of the cluster after the whole matrix is
// read, which is exact for a covariance.
// SINEX names no reference frame: the estimates' frame comes from
// --sinex-frame (NetworkReadOptions::sinex_frame), their epoch from
// REF_EPOCH.

#include <Eigen/Cholesky>

#include <cmath>
#include <map>
#include <optional>
#include <initializer_list>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/base/number_text.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"

namespace geoanchor::io::detail {
namespace {

struct Estimate {
  std::string type, code, pt, soln, epoch, unit;
  double value = 0.0;
  std::optional<double> std_dev;
  std::size_t line = 0;
};

// A parameter index (INDEX, PARA1, PARA2) is a 5-digit field: a larger
// value (1e300 in the same columns) is no parameter and no std::size_t.
constexpr double kMaxIndex = 99999.0;

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return "";
  return std::string(s.substr(b, s.find_last_not_of(" \t\r") - b + 1));
}

// Columns first..last (1-based, inclusive) of a line, trimmed; "" past its end.
std::string columns(const std::string& line, std::size_t first, std::size_t last) {
  if (line.size() < first) return "";
  return trim(std::string_view(line).substr(first - 1, last - first + 1));
}

class Reader {
 public:
  Reader(std::string_view source, geodesy::Network& net, const NetworkReadOptions& o)
      : source_(source), net_(net), options_(o), builder_(net) {}

  void parse(std::string_view text) {
    std::size_t at = 0, line_no = 0;
    bool ended = false;
    if (text.substr(0, 3) == "\xEF\xBB\xBF") at = 3;  // a UTF-8 byte-order mark
    std::string block;
    while (at < text.size()) {
      std::size_t end = text.find_first_of("\r\n", at);
      if (end == std::string_view::npos) end = text.size();
      std::string line(text.substr(at, end - at));
      at = end + 1;
      if (end < text.size() && text[end] == '\r' && at < text.size() && text[at] == '\n') ++at;  // CRLF
      ++line_no;
      if (ended) {
        if (!trim(line).empty()) fail(line_no, "text after %ENDSNX");
        continue;
      }
      if (line_no == 1) {
        header(line);
        continue;
      }
      if (line.empty()) continue;
      const char c = line[0];
      if (c == '*') continue;
      if (c == '%') {
        if (line.rfind("%ENDSNX", 0) != 0) fail(line_no, "'" + line + "': expected %ENDSNX");
        if (!block.empty()) fail(line_no, "%ENDSNX inside block +" + block + " (no -" + block + ")");
        ended = true;
        continue;
      }
      if (c == '+') {
        if (!block.empty()) fail(line_no, "block " + trim(line) + " starts inside +" + block);
        block = trim(std::string_view(line).substr(1));
        {
          // The blocks of SINEX 2.02; the ones this reader does not use do
          // not change what the estimates and their covariance mean.
          static const std::set<std::string> kKnown = {
              "FILE/REFERENCE", "FILE/COMMENT", "INPUT/HISTORY", "INPUT/FILES", "INPUT/ACKNOWLEDGEMENTS", "INPUT/ACKNOWLEDGMENTS",
              "NUTATION/DATA", "PRECESSION/DATA", "SOURCE/ID", "SITE/ID", "SITE/DATA", "SITE/RECEIVER", "SITE/ANTENNA",
              "SITE/GPS_PHASE_CENTER", "SITE/GAL_PHASE_CENTER", "SITE/ECCENTRICITY", "SATELLITE/ID", "SATELLITE/PHASE_CENTER",
              "BIAS/EPOCHS", "SOLUTION/EPOCHS", "SOLUTION/STATISTICS", "SOLUTION/ESTIMATE", "SOLUTION/APRIORI",
              "SOLUTION/DISCONTINUITY", "SOLUTION/NORMAL_EQUATION_VECTOR"};
          const std::string head = block.substr(0, block.find(' '));
          if (!kKnown.count(block) && head != "SOLUTION/MATRIX_ESTIMATE" && head != "SOLUTION/MATRIX_APRIORI" &&
              head != "SOLUTION/NORMAL_EQUATION_MATRIX") {
            fail(line_no, "block +" + block + " is not a SINEX 2.02 block");
          }
        }
        if (block.rfind("SOLUTION/MATRIX_ESTIMATE", 0) == 0) matrix_start(block, line_no);
        continue;
      }
      if (c == '-') {
        const std::string closing = trim(std::string_view(line).substr(1));
        if (closing != block) fail(line_no, "-" + closing + " closes +" + (block.empty() ? std::string("(no block)") : block));
        block.clear();
        continue;
      }
      if (c != ' ') fail(line_no, "a data line must start with a blank (first character '" + std::string(1, c) + "')");
      if (block == "SOLUTION/ESTIMATE") estimate(line, line_no);
      else if (block.rfind("SOLUTION/MATRIX_ESTIMATE", 0) == 0) matrix_row(line, line_no);
      // Other blocks (SITE/ID, SOLUTION/EPOCHS, SOLUTION/APRIORI, …) do
      // not change what the estimates and their covariance mean.
    }
    if (!ended) fail(line_no, "no %ENDSNX line: the file is truncated");
    finish();
  }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, "E_SINEX", source_ + ":" + std::to_string(line) + ": " + what);
  }
  std::string where(std::size_t line) const { return source_ + ":" + std::to_string(line); }

  double number(const std::string& text, std::size_t line, const std::string& what) const {
    std::string t = trim(text);
    for (char& ch : t) {
      if (ch == 'D' || ch == 'd') ch = 'E';  // Fortran exponents
    }
    if (!t.empty() && t[0] == '+') t.erase(0, 1);
    const auto v = parse_finite_double(t);
    if (!v) fail(line, what + " '" + text + "' is not a number");
    return *v;
  }

  void header(const std::string& line) {
    if (line.rfind("%=SNX", 0) != 0) fail(1, "the first line must be the %=SNX header");
    std::istringstream in(line.substr(5));
    std::vector<std::string> t;
    for (std::string w; in >> w;) t.push_back(w);
    // version agency created agency start end technique count constraint [types]
    if (t.size() < 9) fail(1, "the %=SNX header has " + std::to_string(t.size()) + " fields after %=SNX; expected at least 9");
    if (t[0].rfind("1.", 0) != 0 && t[0].rfind("2.", 0) != 0) {
      fail(1, "SINEX version " + t[0] + "; geoanchor reads versions 1.xx and 2.xx (2.02 described)");
    }
    constraint_code_ = t[8];
    if (constraint_code_ != "0" && constraint_code_ != "1" && constraint_code_ != "2") {
      fail(1, "constraint code '" + constraint_code_ + "' in the header; expected 0, 1 or 2");
    }
  }

  // The blanks between fixed-width fields (1-based columns): a field
  // shifted into its neighbour is refused, never read as another number.
  void separators(const std::string& line, std::size_t line_no, std::initializer_list<std::size_t> columns_between,
                  const char* block) const {
    for (std::size_t c : columns_between) {
      if (line.size() >= c && line[c - 1] != ' ') {
        fail(line_no, std::string(block) + ": column " + std::to_string(c) + " holds '" + std::string(1, line[c - 1]) +
                          "' where the fixed-column layout has a blank: a field is shifted");
      }
    }
  }

  void estimate(const std::string& line, std::size_t line_no) {
    separators(line, line_no, {1, 7, 14, 19, 22, 27, 40, 45, 47, 69}, "SOLUTION/ESTIMATE");
    const std::string index_text = columns(line, 2, 6);
    const double index = number(index_text, line_no, "INDEX");
    if (!(index >= 1 && index <= kMaxIndex) || index != std::floor(index)) {
      fail(line_no, "INDEX " + index_text + " must be a whole number from 1 to 99999");
    }
    Estimate e;
    e.type = columns(line, 8, 13);
    e.code = columns(line, 15, 18);
    e.pt = columns(line, 20, 21);
    e.soln = columns(line, 23, 26);
    e.epoch = columns(line, 28, 39);
    e.unit = columns(line, 41, 44);
    e.value = number(columns(line, 48, 68), line_no, "ESTIMATED VALUE");
    const std::string sd = columns(line, 70, 80);
    if (!sd.empty()) e.std_dev = number(sd, line_no, "STD_DEV");
    e.line = line_no;
    const std::size_t i = static_cast<std::size_t>(index);
    if (estimates_.count(i)) fail(line_no, "INDEX " + index_text + " appears twice (first at line " + std::to_string(estimates_.at(i).line) + ")");
    estimates_[i] = e;
  }

  void matrix_start(const std::string& block, std::size_t line_no) {
    std::istringstream in(block);
    std::string name, triangle, kind;
    in >> name >> triangle >> kind;
    if (triangle != "L" && triangle != "U") fail(line_no, "+" + block + ": expected L or U after SOLUTION/MATRIX_ESTIMATE");
    if (kind != "COVA" && kind != "CORR" && kind != "INFO") fail(line_no, "+" + block + ": expected COVA, CORR or INFO");
    if (!matrix_kind_.empty()) fail(line_no, "a second SOLUTION/MATRIX_ESTIMATE block (the first at line " + std::to_string(matrix_line_) + ")");
    matrix_triangle_ = triangle;
    matrix_kind_ = kind;
    matrix_line_ = line_no;
  }

  void matrix_row(const std::string& line, std::size_t line_no) {
    std::istringstream in(line);
    std::vector<std::string> t;
    for (std::string w; in >> w;) t.push_back(w);
    if (t.size() < 3 || t.size() > 5) {
      fail(line_no, "a matrix line holds PARA1 PARA2 and 1 to 3 values; found " + std::to_string(t.size()) + " fields");
    }
    const double r = number(t[0], line_no, "PARA1"), c = number(t[1], line_no, "PARA2");
    if (!(r >= 1 && r <= kMaxIndex && c >= 1 && c <= kMaxIndex) || r != std::floor(r) || c != std::floor(c)) {
      fail(line_no, "PARA1 and PARA2 must be whole numbers from 1 to 99999 (parameter indices)");
    }
    for (std::size_t k = 2; k < t.size(); ++k) {
      const std::size_t row = static_cast<std::size_t>(r), col = static_cast<std::size_t>(c) + (k - 2);
      if (matrix_triangle_ == "L" ? col > row : col < row) {
        fail(line_no, "element (" + std::to_string(row) + ", " + std::to_string(col) + ") is outside the " +
                          (matrix_triangle_ == "L" ? "lower" : "upper") + " triangle the block names");
      }
      const auto [it, fresh] = elements_.emplace(std::make_pair(std::min(row, col), std::max(row, col)), number(t[k], line_no, "matrix element"));
      if (!fresh) fail(line_no, "matrix element (" + std::to_string(row) + ", " + std::to_string(col) + ") given twice");
    }
  }

  void finish() {
    if (estimates_.empty()) fail(1, "no SOLUTION/ESTIMATE block: nothing to read");
    if (matrix_kind_.empty()) {
      fail(1, "no SOLUTION/MATRIX_ESTIMATE block: the estimates' covariance is needed (their STD_DEV alone leaves out the "
              "correlations)");
    }
    if (!options_.sinex_frame) {
      fail(1, "SINEX names no reference frame: give the frame of its estimates with --sinex-frame (a frame of the catalog, e.g. ITRF2014)");
    }
    const std::size_t n = estimates_.rbegin()->first;
    if (estimates_.size() != n) fail(1, "SOLUTION/ESTIMATE has " + std::to_string(estimates_.size()) + " parameters but indices up to " + std::to_string(n));
    Eigen::MatrixXd m = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
    for (const auto& [rc, v] : elements_) {
      if (rc.second > n) fail(matrix_line_, "matrix element (" + std::to_string(rc.first) + ", " + std::to_string(rc.second) + ") beyond the " + std::to_string(n) + " parameters");
      m(static_cast<Eigen::Index>(rc.first - 1), static_cast<Eigen::Index>(rc.second - 1)) = v;
      m(static_cast<Eigen::Index>(rc.second - 1), static_cast<Eigen::Index>(rc.first - 1)) = v;
    }
    if (matrix_kind_ == "CORR") {
      const Eigen::VectorXd sd = m.diagonal();
      for (Eigen::Index i = 0; i < m.rows(); ++i) {
        if (!(sd(i) > 0.0)) fail(matrix_line_, "CORR: standard deviation of parameter " + std::to_string(i + 1) + " is " + format_shortest(sd(i)));
      }
      for (Eigen::Index i = 0; i < m.rows(); ++i) {
        for (Eigen::Index j = 0; j < m.cols(); ++j) m(i, j) = i == j ? sd(i) * sd(i) : m(i, j) * sd(i) * sd(j);
      }
    } else if (matrix_kind_ == "INFO") {
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(m);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 0.0) {
        fail(matrix_line_, "INFO: the normal matrix is singular or not positive definite (a constraint-free solution "
                           "with a datum defect?); its covariance does not exist");
      }
      m = ldlt.solve(Eigen::MatrixXd::Identity(m.rows(), m.cols()));
    }

    // The matrix's standard deviations are the estimates' STD_DEV (printed
    // with 5 digits): a matrix of another kind than its block says, or of
    // other units, is refused.
    constexpr double kStdDevAgreement = 2e-3;
    for (const auto& [i, e] : estimates_) {
      if (!e.std_dev) continue;
      const double from_matrix = std::sqrt(std::max(0.0, m(static_cast<Eigen::Index>(i - 1), static_cast<Eigen::Index>(i - 1))));
      if (!(std::fabs(from_matrix - *e.std_dev) <= kStdDevAgreement * std::max(*e.std_dev, from_matrix) + 1e-12)) {
        fail(e.line, "STD_DEV " + format_shortest(*e.std_dev) + " of parameter " + std::to_string(i) + " (" + e.type + " " + e.code +
                         ") disagrees with the " + matrix_kind_ + " matrix's " + format_shortest(from_matrix) +
                         " (block +SOLUTION/MATRIX_ESTIMATE at line " + std::to_string(matrix_line_) + ")");
      }
    }

    // The stations: X, Y, Z of each site (code, point, solution).
    struct Site {
      std::array<std::optional<std::size_t>, 3> index;
      std::string epoch;
      std::size_t line = 0;
    };
    std::map<std::tuple<std::string, std::string, std::string>, Site> sites;
    std::vector<std::tuple<std::string, std::string, std::string>> order;
    std::set<std::string> other_types;
    for (const auto& [i, e] : estimates_) {
      int axis = e.type == "STAX" ? 0 : e.type == "STAY" ? 1 : e.type == "STAZ" ? 2 : -1;
      if (axis < 0) {
        other_types.insert(e.type);
        continue;
      }
      if (e.unit != "m") fail(e.line, e.type + " in unit '" + e.unit + "'; expected m");
      const auto key = std::make_tuple(e.code, e.pt, e.soln);
      auto [it, fresh] = sites.emplace(key, Site{});
      if (fresh) order.push_back(key), it->second.line = e.line, it->second.epoch = e.epoch;
      if (it->second.index[static_cast<std::size_t>(axis)]) fail(e.line, e.type + " of " + e.code + " given twice");
      if (e.epoch != it->second.epoch) fail(e.line, e.code + ": REF_EPOCH " + e.epoch + " differs from " + it->second.epoch + " of its other coordinates");
      it->second.index[static_cast<std::size_t>(axis)] = i - 1;
    }
    if (sites.empty()) fail(1, "SOLUTION/ESTIMATE holds no station coordinates (STAX, STAY, STAZ)");
    std::map<std::string, std::size_t> per_code;
    for (const auto& key : order) ++per_code[std::get<0>(key)];
    std::string epoch;
    std::vector<std::size_t> rows;
    geodesy::NetworkMeasurement msr;
    msr.kind = geodesy::MeasurementKind::gnss_points;
    for (const auto& key : order) {
      const Site& s = sites.at(key);
      const auto& [code, pt, soln] = key;
      for (int k = 0; k < 3; ++k) {
        if (!s.index[static_cast<std::size_t>(k)]) fail(s.line, code + " has no STA" + std::string(1, "XYZ"[k]));
      }
      if (epoch.empty()) epoch = s.epoch;
      if (s.epoch != epoch) {
        fail(s.line, code + ": REF_EPOCH " + s.epoch + " differs from " + epoch + "; geoanchor reads one epoch per SINEX file");
      }
      // The station's name: its 4-character code, with point and solution when the code repeats.
      const std::string id = per_code[code] == 1 ? code : code + "_" + pt + "_" + soln;
      msr.stations.push_back(builder_.reference(id, where(s.line)));
      for (int k = 0; k < 3; ++k) rows.push_back(*s.index[static_cast<std::size_t>(k)]);
    }
    const Eigen::Index k = static_cast<Eigen::Index>(rows.size());
    msr.value.resize(k);
    msr.covariance.resize(k, k);
    for (Eigen::Index a = 0; a < k; ++a) {
      msr.value(a) = estimates_.at(rows[static_cast<std::size_t>(a)] + 1).value;
      for (Eigen::Index b = 0; b < k; ++b) {
        msr.covariance(a, b) = m(static_cast<Eigen::Index>(rows[static_cast<std::size_t>(a)]), static_cast<Eigen::Index>(rows[static_cast<std::size_t>(b)]));
      }
    }
    const std::size_t first_line = sites.at(order.front()).line;
    if (options_.sinex_frame->epoch()) {
      fail(first_line, "--sinex-frame " + options_.sinex_frame->to_string() + " gives an epoch; the estimates' epoch is their REF_EPOCH");
    }
    msr.frame = geodesy::Frame::parse(options_.sinex_frame->name() + "@" +
                                          geodesy::format_decimal_year(geodesy::DecimalYear{sinex_epoch_year(epoch, first_line)}),
                                      where(first_line) + ": REF_EPOCH");
    if (!net_.frame) {
      // The first input that names a frame gives the network its own (as DynaML does).
      net_.frame = msr.frame;
      if (const auto e = frame_ellipsoid(*net_.frame, "--sinex-frame")) {
        net_.ellipsoid = e->ellipsoid;
        net_.ellipsoid_stated = true;
      }
    }
    msr.source = where(sites.at(order.front()).line) + " (SOLUTION/ESTIMATE, " + std::to_string(order.size()) + " stations)";
    net_.measurements.push_back(std::move(msr));
    if (!other_types.empty()) {
      std::string list;
      for (const auto& t : other_types) list += (list.empty() ? "" : ", ") + t;
      net_.warnings.push_back(source_ + ": parameters " + list + " are not station coordinates: the positions' covariance is "
                              "their marginal one, the other parameters left out");
    }
    if (constraint_code_ != "2") {
      net_.warnings.push_back(source_ + ": the header's constraint code is " + constraint_code_ + " (" +
                              (constraint_code_ == "0" ? "tight" : "significant") +
                              " constraints): the covariance carries the solution's own datum constraints; a loosely "
                              "constrained solution (code 2) is the one to adjust");
    }
  }

  // YY:DDD:SSSSS as a decimal year.
  double sinex_epoch_year(const std::string& text, std::size_t line) const {
    int yy = 0, doy = 0, sec = 0;
    char c1 = 0, c2 = 0;
    std::istringstream in(text);
    if (!(in >> yy >> c1 >> doy >> c2 >> sec) || c1 != ':' || c2 != ':' || yy < 0 || yy > 99) {
      fail(line, "REF_EPOCH '" + text + "'; expected YY:DDD:SSSSS");
    }
    if (yy == 0 && doy == 0 && sec == 0) fail(line, "REF_EPOCH 00:000:00000 (unknown); the estimates need their epoch");
    const int year = yy <= 50 ? 2000 + yy : 1900 + yy;
    const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
    const int days = leap ? 366 : 365;
    if (doy < 1 || doy > days || sec < 0 || sec > 86400) fail(line, "REF_EPOCH '" + text + "': day or seconds out of range");
    return year + ((doy - 1) + sec / 86400.0) / days;
  }

  std::string source_;
  geodesy::Network& net_;
  const NetworkReadOptions& options_;
  NetworkBuilder builder_;
  std::string constraint_code_;
  std::map<std::size_t, Estimate> estimates_;
  std::string matrix_triangle_, matrix_kind_;
  std::size_t matrix_line_ = 0;
  std::map<std::pair<std::size_t, std::size_t>, double> elements_;
};

}  // namespace

void read_sinex(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  Reader(source, into, options).parse(text);
}

}  // namespace geoanchor::io::detail
