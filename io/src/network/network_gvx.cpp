// NGS GNSS Vector Exchange (GVX) 1.0 read with expat into records of
// checked leaves (network_gvx.hpp); what the records mean is
// network_gvx_records.cpp's.
//
// The format as NGS publishes it (the XML schema "GVX Schema.xml" of
// github.com/noaa-ngs/ngs_xml, schema version 1.0 of February 2021, and the
// narrative description of the same date; docs/network-format.md):
//  - the root <GVX VERSION="1.0"> holds, in this order, one SOURCE_DATA and
//    one PROJECT_INFORMATION, REFERENCE_SYSTEMs, EQUIPMENT, SURVEY_SETUPs,
//    POINTs, GNSS_VECTORs, SESSIONs and REMARKs; no namespace;
//  - every other value is an element's text; each element of a record
//    appears at most once (xs:all), in any order;
//  - records refer to each other by ID ([0-9A-Za-z._]+, unique in the file).
//
// Every element of the schema is read here; one the schema does not have, an
// attribute, a value of the wrong type or a second copy of an element is an
// error naming it (E_GVX). NGS's own writer (ngs_xml_writer.py, same
// repository) writes every optional element, empty when it has no value, and
// puts a vector's ECEF_DELTAS and CORRELATION_MATRIX inside its
// QUALITY_CONTROL: an empty element is read as absent, and both places of
// the two are read (the same element in both is refused as a second copy).

#include "network/network_gvx.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io::detail::gvx {

const Leaf* Record::find(std::string_view path) const {
  for (const auto& l : leaves) {
    if (l.path == path) return &l;
  }
  return nullptr;
}

const std::string& Record::text(std::string_view path) const {
  static const std::string kNone;
  const Leaf* l = find(path);
  return l ? l->text : kNone;
}

namespace {

enum class Type { text, number, integer, unsigned_integer, date_time, boolean, id, choice };

// One element of the schema that holds text: the record it is in, its path
// below the record, its type and (choice) the values it may take.
struct Field {
  std::string_view record, path;
  Type type;
  std::string_view choices = {};  // '|' between the values
};

constexpr std::string_view kSolutionTypes = "Single-baseRTK|NetworkRTK|Post-processed";
constexpr std::string_view kPointTypes = "Keyed-in|Code|Float|Fixed|PartialFixed|Adjusted|PPP Solution";

// GVX 1.0's schema, every element that holds text (the containers are the
// paths' prefixes).
constexpr std::array kFields = {
    Field{"SOURCE_DATA", "NAME", Type::text},
    Field{"SOURCE_DATA", "CREATED_DATE", Type::date_time},
    Field{"SOURCE_DATA", "APPLICATION/NAME", Type::text},
    Field{"SOURCE_DATA", "APPLICATION/VERSION", Type::text},
    Field{"SOURCE_DATA", "APPLICATION/MANUFACTURER", Type::text},
    Field{"SOURCE_DATA", "APPLICATION/MANUFACTURER_URL", Type::text},
    Field{"SOURCE_DATA", "CONVERTED_BY/SOFTWARE_NAME", Type::text},
    Field{"SOURCE_DATA", "CONVERTED_BY/VERSION", Type::text},
    Field{"SOURCE_DATA", "CONVERTED_BY/SOFTWARE_URL", Type::text},
    Field{"SOURCE_DATA", "CONVERTED_BY/CONVERTED_DATE", Type::date_time},
    Field{"PROJECT_INFORMATION", "TITLE", Type::text},
    Field{"PROJECT_INFORMATION", "EMAIL_ADDRESS", Type::text},
    Field{"PROJECT_INFORMATION", "PARTY_CHIEF", Type::text},
    Field{"PROJECT_INFORMATION", "AGENCY", Type::text},
    Field{"PROJECT_INFORMATION", "START_DATE", Type::date_time},
    Field{"PROJECT_INFORMATION", "END_DATE", Type::date_time},
    Field{"PROJECT_INFORMATION", "REMARK", Type::text},
    Field{"REFERENCE_SYSTEM", "ID", Type::id},
    Field{"REFERENCE_SYSTEM", "CODE", Type::text},
    Field{"REFERENCE_SYSTEM", "NAME", Type::text},
    Field{"REFERENCE_SYSTEM", "LINEAR_UNIT/NAME", Type::choice, "meters|metres"},
    Field{"REFERENCE_SYSTEM", "LINEAR_UNIT/SIGNIFICANT_DIGITS", Type::unsigned_integer},
    Field{"REFERENCE_SYSTEM", "LINEAR_UNIT/CONVERSION_FACTOR", Type::number},
    Field{"REFERENCE_SYSTEM", "ANGULAR_UNIT/NAME", Type::choice, "decimal degrees"},
    Field{"REFERENCE_SYSTEM", "ANGULAR_UNIT/SIGNIFICANT_DIGITS", Type::unsigned_integer},
    Field{"REFERENCE_SYSTEM", "ANGULAR_UNIT/CONVERSION_FACTOR", Type::number},
    Field{"REFERENCE_SYSTEM", "REMARK", Type::text},
    Field{"EQUIPMENT", "ID", Type::id},
    Field{"EQUIPMENT", "RECEIVER/TYPE", Type::text},
    Field{"EQUIPMENT", "RECEIVER/SERIAL_NUMBER", Type::text},
    Field{"EQUIPMENT", "RECEIVER/FIRMWARE_VERSION", Type::text},
    Field{"EQUIPMENT", "ANTENNA/TYPE", Type::text},
    Field{"EQUIPMENT", "ANTENNA/CALIBRATION_TYPE", Type::choice, "Absolute|Relative|Unknown"},
    Field{"EQUIPMENT", "ANTENNA/CALIBRATION_SOURCE", Type::text},
    Field{"EQUIPMENT", "ANTENNA/SERIAL_NUMBER", Type::text},
    Field{"SURVEY_SETUP", "ID", Type::id},
    Field{"SURVEY_SETUP", "SOLUTION_TYPE", Type::choice, kSolutionTypes},
    Field{"SURVEY_SETUP", "OPERATOR", Type::text},
    Field{"SURVEY_SETUP", "PROCESSING_SOFTWARE/NAME", Type::text},
    Field{"SURVEY_SETUP", "PROCESSING_SOFTWARE/VERSION", Type::text},
    Field{"SURVEY_SETUP", "PROCESSING_SOFTWARE/SOFTWARE_URL", Type::text},
    Field{"SURVEY_SETUP", "CORRECTOR_FORMAT", Type::text},
    Field{"SURVEY_SETUP", "NETWORKRTK/NAME", Type::text},
    Field{"SURVEY_SETUP", "NETWORKRTK/MOUNT_POINT", Type::text},
    Field{"SURVEY_SETUP", "NETWORKRTK/TYPE", Type::choice, "VRS|MAC|MAX|i-MAX|FKP|RTX|Other"},
    Field{"SURVEY_SETUP", "NETWORKRTK/IP_ADDRESS", Type::text},
    Field{"SURVEY_SETUP", "NETWORKRTK/IP_PORT", Type::unsigned_integer},
    Field{"SURVEY_SETUP", "REMARK", Type::text},
    Field{"POINT", "ID", Type::id},
    Field{"POINT", "NAME", Type::text},
    Field{"POINT", "CODE", Type::text},
    Field{"POINT", "EQUIPMENT_ID", Type::id},
    Field{"POINT", "ARP_HEIGHT", Type::number},
    Field{"POINT", "POINT_TYPE", Type::choice, kPointTypes},
    Field{"POINT", "NETWORK_LOCATION", Type::choice, "Inside|Outside|Unknown"},
    Field{"POINT", "TILT_COMPENSATOR", Type::boolean},
    Field{"POINT", "COORDINATES/REFERENCE_SYSTEM_ID", Type::id},
    Field{"POINT", "COORDINATES/EPOCH", Type::number},
    Field{"POINT", "COORDINATES/GEODETIC_COORDINATES/LATITUDE", Type::number},
    Field{"POINT", "COORDINATES/GEODETIC_COORDINATES/LONGITUDE", Type::number},
    Field{"POINT", "COORDINATES/GEODETIC_COORDINATES/ELLIPSOIDAL_HEIGHT", Type::number},
    Field{"POINT", "COORDINATES/GEOCENTRIC_COORDINATES/X", Type::number},
    Field{"POINT", "COORDINATES/GEOCENTRIC_COORDINATES/Y", Type::number},
    Field{"POINT", "COORDINATES/GEOCENTRIC_COORDINATES/Z", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/SDN", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/SDE", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/SDU", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/PNE", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/PNU", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX_LOCAL/PEU", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/SDX", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/SDY", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/SDZ", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/PXY", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/PXZ", Type::number},
    Field{"POINT", "COORDINATES/CORRELATION_MATRIX/PYZ", Type::number},
    Field{"GNSS_VECTOR", "ID", Type::id},
    Field{"GNSS_VECTOR", "INITIAL_POINT_ID", Type::id},
    Field{"GNSS_VECTOR", "TERMINAL_POINT_ID", Type::id},
    Field{"GNSS_VECTOR", "SURVEY_SETUP_ID", Type::id},
    Field{"GNSS_VECTOR", "OBSERVATION_TIME/START", Type::date_time},
    Field{"GNSS_VECTOR", "OBSERVATION_TIME/END", Type::date_time},
    Field{"GNSS_VECTOR", "OBSERVATION_TIME/UTC_OFFSET", Type::number},
    Field{"GNSS_VECTOR", "OBSERVATION_TIME/LEAP_SECONDS", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/EPOCHS_USED", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/MASK/ELEVATION", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/MASK/PDOP_MASK", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/RMS", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/DILUTION_PRECISION/GDOP", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/DILUTION_PRECISION/HDOP", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/DILUTION_PRECISION/PDOP", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/DILUTION_PRECISION/TDOP", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/DILUTION_PRECISION/VDOP", Type::number},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/TOTAL", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/GPS", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/GLONASS", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/GALILEO", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/QZSS", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/SATELLITE_USED/BEIDOU", Type::integer},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/ORBIT/TYPE", Type::choice,
          "Broadcast|Ultra-rapid predicted half|Ultra-rapid observed half|Rapid|Final"},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/ORBIT/SOURCE", Type::text},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID", Type::id},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/ORBIT/DOWNLOAD_DATE", Type::date_time},
    Field{"GNSS_VECTOR", "QUALITY_CONTROL/CORRECTOR_AGE", Type::integer},
    Field{"GNSS_VECTOR", "ECEF_DELTAS/DX", Type::number},
    Field{"GNSS_VECTOR", "ECEF_DELTAS/DY", Type::number},
    Field{"GNSS_VECTOR", "ECEF_DELTAS/DZ", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/SDX", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/SDY", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/SDZ", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/PXY", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/PXZ", Type::number},
    Field{"GNSS_VECTOR", "CORRELATION_MATRIX/PYZ", Type::number},
    Field{"REMARK", "", Type::text},
};

constexpr std::array<std::string_view, 8> kRecords = {"SOURCE_DATA", "PROJECT_INFORMATION", "REFERENCE_SYSTEM", "EQUIPMENT",
                                                      "SURVEY_SETUP", "POINT", "GNSS_VECTOR", "REMARK"};

const Field* leaf_field(std::string_view record, std::string_view path) {
  for (const auto& f : kFields) {
    if (f.record == record && f.path == path) return &f;
  }
  return nullptr;
}

// Whether `path` is a container of `record` (a prefix of a leaf's path).
bool is_container(std::string_view record, std::string_view path) {
  for (const auto& f : kFields) {
    if (f.record == record && f.path.size() > path.size() && f.path.substr(0, path.size()) == path && f.path[path.size()] == '/') {
      return true;
    }
  }
  return false;
}

// The elements the schema has directly in `path` of `record` ("" the record itself).
std::string children_of(std::string_view record, std::string_view path) {
  std::vector<std::string_view> names;
  for (const auto& f : kFields) {
    if (f.record != record || f.path.empty()) continue;
    std::string_view rest = f.path;
    if (!path.empty()) {
      if (rest.size() <= path.size() || rest.substr(0, path.size()) != path || rest[path.size()] != '/') continue;
      rest = rest.substr(path.size() + 1);
    }
    const std::string_view name = rest.substr(0, rest.find('/'));
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  std::string out;
  for (const auto n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

bool blank(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; });
}

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  return std::string(s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1));
}

bool digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// The problem with `text` as a value of `f`, or "" when it is one.
std::string type_problem(const Field& f, const std::string& text) {
  switch (f.type) {
    case Type::text: return {};
    case Type::number:
      return parse_finite_double(text) ? std::string() : "is not a finite number (a decimal number, e.g. 1.2345)";
    case Type::integer: {
      const std::string_view d = !text.empty() && (text[0] == '-' || text[0] == '+') ? std::string_view(text).substr(1) : text;
      return digits(d) && d.size() <= 18 ? std::string() : "is not an integer";
    }
    case Type::unsigned_integer: return digits(text) && text.size() <= 9 ? std::string() : "is not a whole number ≥ 0";
    case Type::date_time:
      return gps_seconds_of(text) ? std::string() : "is not a date and time YYYY-MM-DDThh:mm:ss[.sss][Z] (GPS time)";
    case Type::boolean:
      return text == "true" || text == "false" || text == "1" || text == "0" ? std::string() : "is not a boolean (1, 0, true or false)";
    case Type::id:
      return std::all_of(text.begin(), text.end(),
                         [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_'; })
                 ? std::string()
                 : "is not an identifier (letters, digits, '.' and '_')";
    case Type::choice: {
      std::string_view rest = f.choices;
      std::string list;
      while (!rest.empty()) {
        const std::string_view v = rest.substr(0, rest.find('|'));
        if (v == text) return {};
        list += (list.empty() ? "" : ", ") + std::string(v);
        rest = v.size() < rest.size() ? rest.substr(v.size() + 1) : std::string_view();
      }
      return "is not one of " + list;
    }
  }
  return {};
}

class Reader final : public XmlHandler {
 public:
  Reader(const std::string& source) : source_(source) {}

  Document parse(std::string_view text) {
    xml_.parse(text, source_, "E_GVX");
    if (!root_seen_) fail(1, "no <GVX> element");
    return std::move(doc_);
  }

  void start_element(const std::string& name, const XML_Char** attributes) override {
    const std::size_t at = xml_.line();
    if (!open_.empty() && !blank(text_)) text_in_container(at);
    text_.clear();
    if (open_.empty()) {
      root(name, attributes, at);
      open_.push_back({name, "", false});
      return;
    }
    open_.back().has_children = true;
    if (open_.size() == 1) return record(name, attributes, at);
    no_attributes(name, attributes, at);
    const Open& parent = open_.back();
    // NGS's writer puts a vector's ECEF_DELTAS and CORRELATION_MATRIX in its
    // QUALITY_CONTROL; the schema puts them in the vector.
    std::string path = parent.path.empty() ? name : parent.path + "/" + name;
    if (record_->type == "GNSS_VECTOR" && parent.path == "QUALITY_CONTROL" && (name == "ECEF_DELTAS" || name == "CORRELATION_MATRIX")) {
      path = name;
    }
    if (!leaf_field(record_->type, path) && !is_container(record_->type, path)) {
      const std::string in = parent.path.empty() ? record_->type : parent.path.substr(parent.path.rfind('/') + 1);
      fail(at, "<" + name + "> in <" + in + "> (" + record_->type + " at line " + std::to_string(record_->line) +
                   ") is not an element of GVX 1.0; expected " + children_of(record_->type, parent.path));
    }
    open_.push_back({name, path, false, at});
  }

  void end_element(const std::string&) override {
    const Open o = open_.back();
    open_.pop_back();
    if (open_.empty()) return;  // </GVX>
    const bool leaf = record_ && leaf_field(record_->type, o.path) && !o.has_children;
    if (!leaf && !blank(text_)) text_in_container(xml_.line());
    if (leaf) add_leaf(o);
    text_.clear();
    if (open_.size() == 1) record_ = nullptr;  // the record's end
  }

  void character_data(const char* s, std::size_t n) override { text_.append(s, n); }

 private:
  struct Open {
    std::string name, path;
    bool has_children = false;
    std::size_t line = 0;
  };

  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, "E_GVX", source_ + ":" + std::to_string(line) + ": " + what);
  }

  void text_in_container(std::size_t at) const {
    const std::string t = trim(text_);
    fail(at, "text '" + t.substr(0, 40) + "' in <" + open_.back().name + ">, which holds elements, not text");
  }

  void root(const std::string& name, const XML_Char** attributes, std::size_t at) {
    if (name != "GVX") fail(at, "root element <" + name + ">; expected <GVX> (NGS GNSS Vector Exchange)");
    root_seen_ = true;
    std::optional<std::string> version;
    for (std::size_t i = 0; attributes[i]; i += 2) {
      const std::string key = attributes[i], value = attributes[i + 1];
      if (key == "VERSION") {
        version = value;
      } else if (key != "xmlns:xsi" && key != "xsi:noNamespaceSchemaLocation") {
        fail(at, "<GVX> attribute " + key + "=\"" + value + "\" is not read by geoanchor; expected VERSION (GVX has no namespace)");
      }
    }
    if (!version) fail(at, "<GVX> has no VERSION; expected VERSION=\"1.0\"");
    if (trim(*version) != "1.0") fail(at, "<GVX> VERSION=\"" + *version + "\"; geoanchor reads GVX 1.0");
  }

  void no_attributes(const std::string& name, const XML_Char** attributes, std::size_t at) const {
    if (attributes[0]) {
      fail(at, "<" + name + "> has the attribute " + std::string(attributes[0]) + "=\"" + attributes[1] + "\"; GVX 1.0 gives " +
                   name + " none");
    }
  }

  void record(const std::string& name, const XML_Char** attributes, std::size_t at) {
    if (name == "SESSION") {
      fail(at, "<SESSION> (the cross-correlations of vectors processed together) is not read: GVX 1.0 does not state "
               "how CCM_BLOCK's nine correlations are laid out (by rows or columns, which vector is the row); "
               "remove the SESSION records to adjust the vectors as independent");
    }
    no_attributes(name, attributes, at);
    if (std::find(kRecords.begin(), kRecords.end(), name) == kRecords.end()) {
      fail(at, "<" + name + "> in <GVX> is not an element of GVX 1.0; expected SOURCE_DATA, PROJECT_INFORMATION, "
                            "REFERENCE_SYSTEM, EQUIPMENT, SURVEY_SETUP, POINT, GNSS_VECTOR, SESSION or REMARK");
    }
    if (name == "SOURCE_DATA" || name == "PROJECT_INFORMATION") {
      for (const auto& r : doc_.records) {
        if (r.type == name) fail(at, "a second <" + name + "> (the first at line " + std::to_string(r.line) + "); GVX allows one");
      }
    }
    doc_.records.push_back({name, at, {}});
    record_ = &doc_.records.back();
    open_.push_back({name, "", false, at});
  }

  void add_leaf(const Open& o) {
    const std::string t = trim(text_);
    if (t.empty()) return;  // written empty: absent
    const Field& f = *leaf_field(record_->type, o.path);
    const std::string shown = o.path.empty() ? record_->type : record_->type + "/" + o.path;
    if (const Leaf* before = record_->find(o.path)) {
      fail(o.line, shown + " is given twice (also at line " + std::to_string(before->line) + ")");
    }
    if (const std::string problem = type_problem(f, t); !problem.empty()) {
      fail(o.line, shown + "='" + t + "' " + problem);
    }
    record_->leaves.push_back({o.path, t, o.line});
  }

  std::string source_;
  XmlStream xml_{*this};
  Document doc_;
  Record* record_ = nullptr;  // the record being read
  std::vector<Open> open_;
  std::string text_;
  bool root_seen_ = false;
};

}  // namespace

std::optional<double> gps_seconds_of(std::string_view t) {
  // YYYY-MM-DDThh:mm:ss[.s…][Z]
  if (t.size() < 19 || t[4] != '-' || t[7] != '-' || t[10] != 'T' || t[13] != ':' || t[16] != ':') return std::nullopt;
  if (t.back() == 'Z') t.remove_suffix(1);
  const auto field = [&](std::size_t at, std::size_t n) -> std::optional<int> {
    const std::string_view d = t.substr(at, n);
    if (!digits(d)) return std::nullopt;
    int v = 0;
    std::from_chars(d.data(), d.data() + d.size(), v);
    return v;
  };
  const auto year = field(0, 4), month = field(5, 2), day = field(8, 2), hour = field(11, 2), minute = field(14, 2);
  if (!year || !month || !day || !hour || !minute) return std::nullopt;
  const std::string_view sec_text = t.substr(17);
  if (sec_text.size() < 2 || !digits(sec_text.substr(0, 2))) return std::nullopt;
  if (sec_text.size() > 2 && (sec_text[2] != '.' || !digits(sec_text.substr(3)))) return std::nullopt;
  const auto seconds = parse_finite_double(sec_text);
  // GPS time has no leap second: 60 is no second of it.
  if (!seconds || *seconds >= 60.0 || *hour > 23 || *minute > 59) return std::nullopt;
  const auto days = days_from_civil(*year, *month, *day);
  if (!days) return std::nullopt;
  const auto gps_epoch = days_from_civil(1980, 1, 6);
  return static_cast<double>(*days - *gps_epoch) * 86400.0 + *hour * 3600.0 + *minute * 60.0 + *seconds;
}

std::optional<long> days_from_civil(int year, int month, int day) {
  if (year < 1 || month < 1 || month > 12 || day < 1) return std::nullopt;
  constexpr std::array<int, 12> kDays = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
  if (day > kDays[static_cast<std::size_t>(month - 1)] + (month == 2 && leap ? 1 : 0)) return std::nullopt;
  // Days before the year (proleptic Gregorian, from 0001-01-01), then before the month.
  const long y = year - 1;
  long n = y * 365 + y / 4 - y / 100 + y / 400;
  for (int m = 1; m < month; ++m) n += kDays[static_cast<std::size_t>(m - 1)] + (m == 2 && leap ? 1 : 0);
  return n + day - 1;
}

Document parse_document(std::string_view text, const std::string& source) { return Reader(source).parse(text); }

}  // namespace geoanchor::io::detail::gvx

namespace geoanchor::io::detail {

void read_gvx(std::string_view text, std::string_view source_in, geodesy::Network& into) {
  const std::string source(source_in);
  const gvx::Document doc = gvx::parse_document(text, source);
  gvx::read_records(doc, source, into);
}

}  // namespace geoanchor::io::detail
