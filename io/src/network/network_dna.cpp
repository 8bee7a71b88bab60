// DynAdjust's DNA text files: the station file (.stn) and the measurement
// file (.msr), versions 3.00 and 3.01, fixed columns.
//
// The layout is DynAdjust's own (its User's Guide appendix, and the column
// tables its reader and writer share, include/io/dnaiodnatypes.hpp of
// icsm-au/DynAdjust): a header record
//   !#=DNA 3.01 STN    <created dd.mm.yyyy> <frame> <epoch dd.mm.yyyy> <count>
// (version columns 7–12, file type 13–15, frame 30–43, epoch 44–57, count
// 58–67), '*' comment lines, then one record per line. Each record is read
// into the DynaML reader's element fields (network_dynaml_reader.hpp) and
// finished by the same code as a <DnaStation> or <DnaMeasurement>: a
// network reads the same from DNA text as from DynaML.
//
// Every column a record uses is read; a character anywhere else on the
// line is refused by name (a value shifted by one column is not guessed
// at). docs/network-format.md lists the records and columns.

#include <array>
#include <cctype>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "network/network_dynaml_reader.hpp"
#include "network/network_readers.hpp"

namespace geoanchor::io::detail {
namespace {

using dynaml::Tag;

// A field's place on the line: 0-based start and width.
struct Column {
  std::size_t at = 0, width = 0;
  std::size_t end() const { return at + width; }
};

// The columns of one version (dnaiodnatypes.hpp's tables).
struct Layout {
  // Station records.
  Column name, constraints, coord_type, x, y, height, zone;
  std::size_t description = 0;  // to the end of the line
  // Measurement records.
  Column type{0, 1}, ignore{1, 1}, first, second, third, linear, gnss, vcv[3], scale[4], frame, epoch;
  Column ang_d, ang_m, ang_s, stddev, inst_height, targ_height, msr_id, cluster_id;
};

Layout layout_301() {
  Layout l;
  l.name = {0, 20}, l.constraints = {20, 3}, l.coord_type = {24, 3};
  l.x = {27, 20}, l.y = {47, 20}, l.height = {67, 20}, l.zone = {87, 3}, l.description = 91;
  l.first = {2, 20}, l.second = {22, 20}, l.third = {42, 20}, l.linear = {62, 14}, l.gnss = {62, 20};
  l.vcv[0] = {82, 20}, l.vcv[1] = {102, 20}, l.vcv[2] = {122, 20};
  l.scale[0] = {62, 10}, l.scale[1] = {72, 10}, l.scale[2] = {82, 10}, l.scale[3] = {92, 10};
  l.frame = {102, 20}, l.epoch = {122, 20};
  l.ang_d = {76, 4}, l.ang_m = {80, 2}, l.ang_s = {82, 8}, l.stddev = {90, 9};
  l.inst_height = {99, 7}, l.targ_height = {106, 7}, l.msr_id = {142, 10}, l.cluster_id = {152, 10};
  return l;
}

Layout layout_300() {
  Layout l = layout_301();
  l.x = {27, 14}, l.y = {41, 14}, l.height = {55, 14}, l.zone = {69, 3}, l.description = 73;
  l.gnss = {62, 14};
  l.vcv[0] = {76, 14}, l.vcv[1] = {90, 14}, l.vcv[2] = {104, 14};
  l.scale[0] = {62, 7}, l.scale[1] = {69, 7}, l.scale[2] = {76, 7}, l.scale[3] = {83, 7};
  l.frame = {90, 14}, l.epoch = {104, 14};
  l.msr_id = {118, 10}, l.cluster_id = {128, 10};
  return l;
}

std::string columns(Column c) {
  return c.width == 1 ? "column " + std::to_string(c.at + 1)
                      : "columns " + std::to_string(c.at + 1) + "-" + std::to_string(c.end());
}

// Each field's name in messages, with its columns.
dynaml::Reader::Labels labels(const Layout& l, bool stations) {
  dynaml::Reader::Labels n;
  auto set = [&](Tag t, const std::string& s) { n[static_cast<std::size_t>(t)] = s; };
  for (std::size_t k = 0; k < n.size(); ++k) n[k] = "field " + std::string(dynaml::kTagNames[k]);
  if (stations) {
    set(Tag::Name, "station name (" + columns(l.name) + ")");
    set(Tag::Constraints, "constraints (" + columns(l.constraints) + ")");
    set(Tag::Type, "coordinate type (" + columns(l.coord_type) + ")");
    set(Tag::XAxis, "X, easting or latitude (" + columns(l.x) + ")");
    set(Tag::YAxis, "Y, northing or longitude (" + columns(l.y) + ")");
    set(Tag::Height, "Z or height (" + columns(l.height) + ")");
    set(Tag::HemisphereZone, "hemisphere and zone (" + columns(l.zone) + ")");
    return n;
  }
  set(Tag::Type, "measurement type (column 1)");
  set(Tag::Ignore, "ignore flag (column 2)");
  set(Tag::First, "first station (" + columns(l.first) + ")");
  set(Tag::Second, "second station (" + columns(l.second) + ")");
  set(Tag::Third, "third station (" + columns(l.third) + ")");
  set(Tag::Target, "target (" + columns(l.third) + ")");
  set(Tag::Total, "count (" + columns(l.third) + ")");
  set(Tag::Coords, "coordinate type (" + columns(l.second) + ")");
  set(Tag::Value, "value (" + columns(l.linear) + ", or " + columns(Column{l.ang_d.at, l.ang_s.end() - l.ang_d.at}) +
                      " as degrees, minutes and seconds)");
  set(Tag::StdDev, "standard deviation (" + columns(l.stddev) + ")");
  set(Tag::InstHeight, "instrument height (the first number in " + columns(Column{l.inst_height.at, l.epoch.at - l.inst_height.at}) + ")");
  set(Tag::TargHeight, "target height (the second number in " + columns(Column{l.inst_height.at, l.epoch.at - l.inst_height.at}) + ")");
  set(Tag::Vscale, "V-scale (" + columns(l.scale[0]) + ")");
  set(Tag::Pscale, "P-scale (" + columns(l.scale[1]) + ")");
  set(Tag::Lscale, "L-scale (" + columns(l.scale[2]) + ")");
  set(Tag::Hscale, "H-scale (" + columns(l.scale[3]) + ")");
  set(Tag::ReferenceFrame, "reference frame (" + columns(l.frame) + ")");
  set(Tag::Epoch, "epoch (" + columns(l.epoch) + ")");
  set(Tag::GPSBaseline, "baselines");
  set(Tag::Clusterpoint, "points");
  set(Tag::Directions, "direction records");
  for (Tag t : {Tag::X, Tag::Y, Tag::Z}) set(t, std::string(dynaml::kTagNames[static_cast<std::size_t>(t)]) + " value (" + columns(l.gnss) + ")");
  const Tag sigmas[6] = {Tag::SigmaXX, Tag::SigmaXY, Tag::SigmaXZ, Tag::SigmaYY, Tag::SigmaYZ, Tag::SigmaZZ};
  for (Tag t : sigmas) set(t, "covariance " + std::string(dynaml::kTagNames[static_cast<std::size_t>(t)]).substr(5) + " (" +
                                  columns(Column{l.vcv[0].at, l.vcv[2].end() - l.vcv[0].at}) + ")");
  const Tag blocks[9] = {Tag::m11, Tag::m12, Tag::m13, Tag::m21, Tag::m22, Tag::m23, Tag::m31, Tag::m32, Tag::m33};
  for (Tag t : blocks) set(t, "cross-covariance " + std::string(dynaml::kTagNames[static_cast<std::size_t>(t)]) + " (" +
                                  columns(Column{l.vcv[0].at, l.vcv[2].end() - l.vcv[0].at}) + ")");
  return n;
}

std::string_view trim(std::string_view s) {
  const auto b = s.find_first_not_of(' ');
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(' ') - b + 1);
}

// The file's lines: LF, CR LF and a CR alone each end one.
std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t start = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '\n' && text[i] != '\r') continue;
    lines.push_back(text.substr(start, i - start));
    if (text[i] == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
    start = i + 1;
  }
  if (start < text.size()) lines.push_back(text.substr(start));
  return lines;
}

class DnaReader {
 public:
  DnaReader(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options)
      : lines_(split_lines(text)), source_(source), reader_(source, into, options) {}

  void read();
  std::size_t approximate_heights() const { return reader_.approximate_heights(); }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, "E_DNA", source_ + ":" + std::to_string(line) + ": " + what);
  }
  // One line being read: its text and the columns read so far.
  struct Line {
    std::string_view text;
    std::size_t number = 0;
    std::string used;  // 'x' where a field was read
  };
  Line line(std::size_t index) const {
    return {lines_[index], index + 1, std::string(lines_[index].size(), ' ')};
  }
  static std::string take(Line& l, Column c) {
    if (c.at >= l.text.size()) return {};
    const std::size_t w = std::min(c.width, l.text.size() - c.at);
    for (std::size_t k = c.at; k < c.at + w; ++k) l.used[k] = 'x';
    return std::string(trim(l.text.substr(c.at, w)));
  }
  // Refuses a character outside the fields `l`'s record uses.
  void check_all_read(const Line& l, const std::string& record) const;
  void put(dynaml::Fields& f, Tag tag, Line& l, Column c) const {
    const std::string v = take(l, c);
    if (!v.empty()) f.emplace(tag, v);
  }
  // Degrees, minutes and seconds in their columns, as DynaML's packed DDD.MMSSsss.
  std::string angle(Line& l) const;
  // The next line of a record that continues on several; `what` names it.
  Line next(std::size_t& index, const std::string& what) const;
  bool skipped(std::string_view text) const { return trim(text).empty() || text[0] == '*'; }

  void header();
  void station(Line l);
  void measurement(std::size_t& index);
  void gnss(dynaml::Measurement& m, Line& l, char type, std::size_t& index);
  void heights(dynaml::Measurement& m, Line& l) const;
  void directions(dynaml::Measurement& m, std::size_t count, std::size_t& index);

  std::vector<std::string_view> lines_;
  std::string source_;
  dynaml::Reader reader_;
  Layout layout_;
  dynaml::Reader::Labels labels_;
  bool stations_ = false;
};

void DnaReader::check_all_read(const Line& l, const std::string& record) const {
  for (std::size_t k = 0; k < l.text.size(); ++k) {
    if (l.used[k] == 'x' || l.text[k] == ' ') continue;
    std::size_t e = k;
    while (e < l.text.size() && l.used[e] != 'x' && l.text[e] != ' ') ++e;
    fail(l.number, "'" + std::string(l.text.substr(k, e - k)) + "' in " + columns(Column{k, e - k}) + " is in no field of " +
                       record + " (DNA text is read by column: is a value shifted?)");
  }
}

DnaReader::Line DnaReader::next(std::size_t& index, const std::string& what) const {
  ++index;
  if (index >= lines_.size()) fail(lines_.size(), "the file ends inside " + what);
  return line(index);
}

std::string DnaReader::angle(Line& l) const {
  const std::string d = take(l, layout_.ang_d), m = take(l, layout_.ang_m), s = take(l, layout_.ang_s);
  if (d.empty() && m.empty() && s.empty()) return {};
  const auto digits = [](const std::string& t, bool sign, bool dot) {
    if (t.empty()) return false;
    std::size_t k = sign && (t[0] == '-' || t[0] == '+') ? 1 : 0, dots = 0;
    if (k == t.size()) return false;
    for (; k < t.size(); ++k) {
      if (t[k] == '.' && dot && ++dots == 1) continue;
      if (!std::isdigit(static_cast<unsigned char>(t[k]))) return false;
    }
    return true;
  };
  if (!digits(d, true, false) || !digits(m, false, false) || !digits(s, false, true)) {
    fail(l.number, "angle '" + d + " " + m + " " + s + "' in " +
                       columns(Column{layout_.ang_d.at, layout_.ang_s.end() - layout_.ang_d.at}) +
                       ": expected whole degrees, whole minutes and seconds, e.g. 91 41 49.5000");
  }
  // Packed: degrees, a dot, two digits of minutes, then the seconds' digits
  // (two before their decimal point).
  const std::size_t dot = s.find('.');
  const std::string whole = dot == std::string::npos ? s : s.substr(0, dot);
  const std::string fraction = dot == std::string::npos ? "" : s.substr(dot + 1);
  return d + "." + (m.size() < 2 ? "0" : "") + m + (whole.size() < 2 ? "0" : "") + whole + fraction;
}

void DnaReader::header() {
  // DynAdjust reads the header trimmed (and so its columns count from its
  // first character); a UTF-8 byte-order mark before it is no character.
  if (!lines_.empty() && lines_[0].substr(0, 3) == "\xEF\xBB\xBF") lines_[0].remove_prefix(3);
  if (!lines_.empty()) lines_[0] = trim(lines_[0]);
  if (lines_.empty() || lines_[0].substr(0, 6) != "!#=DNA") fail(1, "no DNA header: expected '!#=DNA 3.01 STN' or '!#=DNA 3.01 MSR' on line 1");
  Line l = line(0);
  const std::string version = take(l, {6, 6}), type = take(l, {12, 3}), created = take(l, {15, 14});
  const std::string frame = take(l, {29, 14}), epoch = take(l, {43, 14}), count = take(l, {57, 10});
  (void)created, (void)count;  // DynAdjust's own use: the file's date and a size hint
  if (version == "3.01") {
    layout_ = layout_301();
  } else if (version == "3.00") {
    layout_ = layout_300();
  } else {
    fail(1, "DNA version '" + version + "' (columns 7-12): geoanchor reads versions 3.00 and 3.01");
  }
  std::string upper;
  for (char c : type) upper += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (upper == "STN") {
    stations_ = true;
  } else if (upper == "MSR") {
    stations_ = false;
  } else if (upper == "GEO") {
    fail(1, "a DNA geoid file (N and deflections per station): give it with --geoid, not as a network input");
  } else {
    fail(1, "DNA file type '" + type + "' (columns 13-15): expected STN (stations) or MSR (measurements)");
  }
  l.used.assign(l.text.size(), 'x');  // the header's own fields
  labels_ = labels(layout_, stations_);
  reader_.begin_dna(labels_, frame, epoch, 1);
}

void DnaReader::station(Line l) {
  dynaml::Station& s = reader_.dna_station(l.number);
  put(s.fields, Tag::Name, l, layout_.name);
  if (!s.fields.count(Tag::Name)) {
    // (DynAdjust skips such a line: its coordinates would go unread.)
    fail(l.number, "a station record without a " + labels_[static_cast<std::size_t>(Tag::Name)] +
                       ": is the line shifted to the right?");
  }
  put(s.fields, Tag::Constraints, l, layout_.constraints);
  put(s.fields, Tag::Type, l, layout_.coord_type);
  put(s.coord, Tag::XAxis, l, layout_.x);
  put(s.coord, Tag::YAxis, l, layout_.y);
  put(s.coord, Tag::Height, l, layout_.height);
  put(s.coord, Tag::HemisphereZone, l, layout_.zone);
  put(s.fields, Tag::Description, l, Column{layout_.description, l.text.size()});
  check_all_read(l, "a station record");
  reader_.finish_dna_station();
}

void DnaReader::directions(dynaml::Measurement& m, std::size_t count, std::size_t& index) {
  for (std::size_t k = 0; k < count; ++k) {
    Line l = next(index, "direction set " + std::to_string(m.line) + " (" + std::to_string(count) + " directions)");
    const std::string type = take(l, layout_.type);
    if (type != "D") fail(l.number, "'" + type + "' in column 1: direction " + std::to_string(k + 1) + " of the set on line " +
                                        std::to_string(m.line) + " must be a D record");
    dynaml::Direction& d = m.directions.push();
    d.line = l.number;
    if (take(l, layout_.ignore) == "*") d.fields.emplace(Tag::Ignore, "*");
    put(d.fields, Tag::Target, l, layout_.third);
    if (const std::string a = angle(l); !a.empty()) d.fields.emplace(Tag::Value, a);
    put(d.fields, Tag::StdDev, l, layout_.stddev);
    put(d.fields, Tag::MeasurementID, l, layout_.msr_id);
    take(l, layout_.cluster_id);  // the set's, as on its first line
    check_all_read(l, "a direction record");
  }
}

// The instrument and target heights of S, V and Z: the two numbers between
// the standard deviation and the epoch (columns 100–122 in 3.01). DynAdjust
// reads them at 100–106 and 107–113, but its own writer has put them one
// column to the right (its dsg.msr sample: "0.0159   0.000  0.000"), where
// those columns would cut a digit off each: read as the numbers written.
void DnaReader::heights(dynaml::Measurement& m, Line& l) const {
  const Column region{layout_.inst_height.at, layout_.epoch.at - layout_.inst_height.at};
  const std::string text = take(l, region);
  std::vector<std::string> tokens;
  std::string token;
  for (char c : text + " ") {
    if (c != ' ') {
      token += c;
    } else if (!token.empty()) {
      tokens.push_back(token);
      token.clear();
    }
  }
  if (tokens.size() > 2) {
    fail(l.number, "'" + text + "' in " + columns(region) + ": expected the instrument and the target height (two numbers)");
  }
  if (!tokens.empty()) m.fields.emplace(Tag::InstHeight, tokens[0]);
  if (tokens.size() == 2) m.fields.emplace(Tag::TargHeight, tokens[1]);
}

// G, X and Y: the first line's scalars, frame and epoch, then per
// baseline or point its values and covariance (lower triangle) and the
// cross-covariance blocks with the later ones.
void DnaReader::gnss(dynaml::Measurement& m, Line& l, char type, std::size_t& index) {
  static constexpr Tag kScale[4] = {Tag::Vscale, Tag::Pscale, Tag::Lscale, Tag::Hscale};
  for (std::size_t k = 0; k < 4; ++k) put(m.fields, kScale[k], l, layout_.scale[k]);
  put(m.fields, Tag::ReferenceFrame, l, layout_.frame);
  put(m.fields, Tag::Epoch, l, layout_.epoch);
  put(m.fields, Tag::MeasurementID, l, layout_.msr_id);
  put(m.fields, Tag::ClusterID, l, layout_.cluster_id);
  check_all_read(l, std::string("a ") + type + " record");
  std::size_t n = 1;
  if (type != 'G') {
    const std::string* total = m.fields.find(Tag::Total);
    const auto count = total ? parse_finite_double(*total) : std::nullopt;
    if (!count || *count < 1 || *count != static_cast<double>(static_cast<std::size_t>(*count)) || *count > 1e6) {
      fail(l.number, labels_[static_cast<std::size_t>(Tag::Total)] + " '" + (total ? *total : "") + "': expected the number of " +
                         (type == 'X' ? "baselines" : "points") + " (1 or more)");
    }
    n = static_cast<std::size_t>(*count);
  }
  const std::string what = std::string(1, type) + " record on line " + std::to_string(l.number);
  static constexpr Tag kSigma[3][3] = {{Tag::SigmaXX}, {Tag::SigmaXY, Tag::SigmaYY}, {Tag::SigmaXZ, Tag::SigmaYZ, Tag::SigmaZZ}};
  static constexpr Tag kBlock[3][3] = {{Tag::m11, Tag::m12, Tag::m13}, {Tag::m21, Tag::m22, Tag::m23}, {Tag::m31, Tag::m32, Tag::m33}};
  for (std::size_t i = 0; i < n; ++i) {
    dynaml::Item& item = m.items.push();
    item.line = l.number;
    item.first = m.firsts.empty() ? "" : m.firsts.back();
    item.second = m.seconds.empty() ? "" : m.seconds.back();
    if (i > 0) {
      // The next baseline's or point's own stations.
      Line h = next(index, what);
      if (take(h, layout_.type) != std::string(1, type)) fail(h.number, "expected the " + std::string(1, type) + " record of item " + std::to_string(i + 1) + " of the " + what);
      take(h, layout_.ignore);
      item.line = h.number;
      item.first = take(h, layout_.first);
      if (type == 'X') item.second = take(h, layout_.second);
      put(item.fields, Tag::MeasurementID, h, layout_.msr_id);
      take(h, layout_.cluster_id);
      check_all_read(h, "the " + what);
    }
    static constexpr Tag kValue[3] = {Tag::X, Tag::Y, Tag::Z};
    for (int r = 0; r < 3; ++r) {
      Line v = next(index, what);
      put(item.fields, kValue[r], v, layout_.gnss);
      for (int c = 0; c <= r; ++c) put(item.fields, kSigma[r][c], v, layout_.vcv[c]);
      take(v, layout_.type), take(v, layout_.ignore), take(v, layout_.msr_id), take(v, layout_.cluster_id);
      check_all_read(v, "a value line of the " + what);
    }
    for (std::size_t b = i + 1; b < n; ++b) {
      dynaml::Fields& block = item.blocks.push();
      for (int r = 0; r < 3; ++r) {
        Line v = next(index, what);
        for (int c = 0; c < 3; ++c) put(block, kBlock[r][c], v, layout_.vcv[c]);
        take(v, layout_.type), take(v, layout_.ignore), take(v, layout_.msr_id), take(v, layout_.cluster_id);
        check_all_read(v, "a covariance line of the " + what);
      }
    }
  }
}

void DnaReader::measurement(std::size_t& index) {
  Line l = line(index);
  const std::string type = take(l, layout_.type);
  dynaml::Measurement& m = reader_.dna_measurement(l.number);
  m.fields.emplace(Tag::Type, type);
  if (const std::string ignore = take(l, layout_.ignore); !ignore.empty()) {
    if (ignore != "*") fail(l.number, "'" + ignore + "' in column 2: expected '*' (ignored) or a blank");
    m.fields.emplace(Tag::Ignore, "*");
  }
  auto station = [&](Tag tag, Column c) {
    const std::string v = take(l, c);
    if (v.empty()) return;
    m.fields.emplace(tag, v);
    if (tag == Tag::First) m.firsts.push().assign(v);
    if (tag == Tag::Second) m.seconds.push().assign(v);
  };
  const char t = type.size() == 1 ? type[0] : '?';
  station(Tag::First, layout_.first);
  switch (t) {
    case 'A': case 'B': case 'K': case 'V': case 'Z': case 'D': {
      station(Tag::Second, layout_.second);
      if (t == 'A') station(Tag::Third, layout_.third);
      if (t == 'D') put(m.fields, Tag::Total, l, layout_.third);
      if (const std::string a = angle(l); !a.empty()) m.fields.emplace(Tag::Value, a);
      put(m.fields, Tag::StdDev, l, layout_.stddev);
      if (t == 'V' || t == 'Z') heights(m, l);
      break;
    }
    case 'C': case 'E': case 'M': case 'S': case 'L': case 'H': case 'R': case 'I': case 'J': case 'P': case 'Q': {
      if (t != 'H' && t != 'R' && t != 'I' && t != 'J' && t != 'P' && t != 'Q') station(Tag::Second, layout_.second);
      put(m.fields, Tag::Value, l, layout_.linear);
      put(m.fields, Tag::StdDev, l, layout_.stddev);
      if (t == 'S') heights(m, l);
      break;
    }
    case 'G': case 'X': case 'Y':
      if (t == 'Y') put(m.fields, Tag::Coords, l, layout_.second);
      else station(Tag::Second, layout_.second);
      if (t != 'G') put(m.fields, Tag::Total, l, layout_.third);
      gnss(m, l, t, index);
      reader_.finish_dna_measurement();
      return;
    default:
      fail(l.number, "measurement type '" + type + "' (column 1): expected one of A, B, C, D, E, G, H, I, J, K, L, M, P, Q, R, S, V, X, Y, Z");
  }
  put(m.fields, Tag::Epoch, l, layout_.epoch);
  put(m.fields, Tag::MeasurementID, l, layout_.msr_id);
  put(m.fields, Tag::ClusterID, l, layout_.cluster_id);
  check_all_read(l, "a " + type + " record");
  if (t == 'D') {
    const std::string* total = m.fields.find(Tag::Total);
    const auto count = total ? parse_finite_double(*total) : std::nullopt;
    if (!count || *count < 0 || *count != static_cast<double>(static_cast<std::size_t>(*count)) || *count > 1e6) {
      fail(l.number, labels_[static_cast<std::size_t>(Tag::Total)] + " '" + (total ? *total : "") +
                         "': expected the number of directions after the reference object");
    }
    directions(m, static_cast<std::size_t>(*count), index);
  }
  reader_.finish_dna_measurement();
}

void DnaReader::read() {
  header();
  for (std::size_t i = 1; i < lines_.size(); ++i) {
    if (skipped(lines_[i])) continue;
    if (lines_[i].find('\t') != std::string_view::npos) {
      fail(i + 1, "a tab character: DNA text is read by column; write the fields with spaces");
    }
    if (stations_) {
      station(line(i));
    } else {
      measurement(i);
    }
  }
}

}  // namespace

void read_dna(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  dynaml::require_ellipsoidal(source, "DNA text", into);
  DnaReader reader(text, source, into, options);
  reader.read();
  dynaml::warn_approximate_heights(source, reader.approximate_heights(), into);
}

}  // namespace geoanchor::io::detail
