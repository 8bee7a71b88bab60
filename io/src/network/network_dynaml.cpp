// DynAdjust's DynaML station and measurement files (XML), read as a stream
// with expat: no tree of the whole file is built.
//
// The format as DynaML.xsd (DynAdjust, sampleData/DynaML.xsd, v1.0.2) and
// DynAdjust's own reader define it (docs/network-format.md lists what is
// read and how):
//  - <DnaXmlFormat referenceframe="GDA2020" epoch="dd.mm.yyyy"> holds
//    <DnaStation> and <DnaMeasurement> elements in any order;
//  - a station's Constraints are three letters C/F: latitude, longitude,
//    height for Type LLH, otherwise east, north, up (UTM, LLh) or X, Y, Z
//    (XYZ); LLH and UTM heights are orthometric, LLh ellipsoidal; latitudes
//    and longitudes are packed sexagesimal DDD.MMSSsss;
//  - angles are packed sexagesimal, their standard deviations arc-seconds;
//    distances and heights metres;
//  - a GNSS baseline's covariance is the upper triangle SigmaXX … SigmaZZ
//    (m²); in a cluster (X, Y) item i carries the blocks cov(i, j) for
//    j = i + 1, …, n − 1 as GPSCovariance / PointCovariance m11 … m33
//    (m_rc: component r of i, component c of j);
//  - Vscale multiplies a GNSS covariance; Pscale, Lscale, Hscale its
//    variances along latitude, longitude and height at the first station;
//  - an empty <Ignore/> is a measurement in use, any text one left out;
//  - a direction set's parent gives the reference object (Second, Value,
//    StdDev) and its <Directions> the other targets.

#include <cctype>
#include <initializer_list>
#include <thread>
#include <system_error>
#include <algorithm>
#include <unordered_map>
#include <cstdint>
#include <bitset>
#include <array>
#include <cmath>

#include <set>
#include <sstream>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io::detail {
namespace {

using geodesy::MeasurementKind;

constexpr double kArcsec = std::numbers::pi / 648000.0;

// DynaML's element names as small numbers: the reader compares and looks
// up tags, not strings (a 10⁵-station file has some 5·10⁶ elements).
enum class Tag : std::uint8_t {
  other,  // a name DynaML.xsd puts nowhere geoanchor reads
  DnaXmlFormat, DnaStation, DnaMeasurement, Name, Constraints, Type, StationCoord, Description, XAxis, YAxis,
  Height, HemisphereZone, Ignore, ReferenceFrame, Epoch, First, Second, Third, Value, StdDev, InstHeight,
  TargHeight, Total, Directions, Vscale, Pscale, Lscale, Hscale, GPSBaseline, Clusterpoint, Coords, Source,
  MeasurementID, ClusterID, X, Y, Z, SigmaXX, SigmaXY, SigmaXZ, SigmaYY, SigmaYZ, SigmaZZ, GPSCovariance,
  PointCovariance, m11, m12, m13, m21, m22, m23, m31, m32, m33, Target,
  count
};
constexpr std::size_t kTagCount = static_cast<std::size_t>(Tag::count);
constexpr std::array<std::string_view, kTagCount> kTagNames = {
    "",
    "DnaXmlFormat", "DnaStation", "DnaMeasurement", "Name", "Constraints", "Type", "StationCoord", "Description",
    "XAxis", "YAxis", "Height", "HemisphereZone", "Ignore", "ReferenceFrame", "Epoch", "First", "Second",
    "Third", "Value", "StdDev", "InstHeight", "TargHeight", "Total", "Directions", "Vscale", "Pscale", "Lscale",
    "Hscale", "GPSBaseline", "Clusterpoint", "Coords", "Source", "MeasurementID", "ClusterID", "X", "Y", "Z",
    "SigmaXX", "SigmaXY", "SigmaXZ", "SigmaYY", "SigmaYZ", "SigmaZZ", "GPSCovariance", "PointCovariance", "m11",
    "m12", "m13", "m21", "m22", "m23", "m31", "m32", "m33", "Target"
};

Tag tag_of(std::string_view name) {
  static const std::unordered_map<std::string_view, Tag> kByName = [] {
    std::unordered_map<std::string_view, Tag> m;
    for (std::size_t k = 1; k < kTagCount; ++k) m.emplace(kTagNames[k], static_cast<Tag>(k));
    return m;
  }();
  const auto it = kByName.find(name);
  return it == kByName.end() ? Tag::other : it->second;
}
std::string name_of(Tag t) { return std::string(kTagNames[static_cast<std::size_t>(t)]); }

// The text values of one element's children, by tag. clear() keeps every
// string's capacity: a file of 10⁶ measurements is read without an
// allocation per value (a map node and two strings each, before).
class Fields {
 public:
  // False when `key` is there already.
  bool emplace(Tag key, std::string_view value) {
    const auto k = static_cast<std::size_t>(key);
    if (present_[k]) return false;
    present_.set(k);
    values_[k].assign(value);
    return true;
  }
  const std::string* find(Tag key) const {
    const auto k = static_cast<std::size_t>(key);
    return present_[k] ? &values_[k] : nullptr;
  }
  bool count(Tag key) const { return find(key) != nullptr; }
  void clear() { present_.reset(); }

 private:
  std::array<std::string, kTagCount> values_;
  std::bitset<kTagCount> present_;
};

// A list whose elements are kept, cleared, for the next element of the
// file (their strings' capacity with them).
template <class T>
class Reused {
 public:
  T& push() {
    if (size_ == items_.size()) items_.emplace_back();
    T& t = items_[size_++];
    t.clear();
    return t;
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T& back() { return items_[size_ - 1]; }
  const T& back() const { return items_[size_ - 1]; }
  const T& front() const { return items_[0]; }
  const T& operator[](std::size_t i) const { return items_[i]; }
  auto begin() const { return items_.begin(); }
  auto end() const { return items_.begin() + static_cast<std::ptrdiff_t>(size_); }
  void clear() { size_ = 0; }

 private:
  std::vector<T> items_;
  std::size_t size_ = 0;
};

// One vector of a GNSS measurement: its values, its own covariance terms
// and the cross-covariance blocks that follow it.
struct Item {
  std::string first, second;
  Fields fields;          // X, Y, Z, SigmaXX, …
  Reused<Fields> blocks;  // m11 … m33
  std::size_t line = 0;
  void clear() {
    first.clear(), second.clear(), fields.clear(), blocks.clear();
    line = 0;
  }
};

struct Direction {
  Fields fields;  // Ignore, Target, Value, StdDev
  std::size_t line = 0;
  void clear() { fields.clear(), line = 0; }
};

struct Measurement {
  Fields fields;                          // Type, Ignore, First, Second, Third, Value, StdDev, …
  Reused<std::string> firsts, seconds;    // as they come, for X and Y clusters
  Reused<Item> items;
  Reused<Direction> directions;
  std::size_t line = 0;
  void clear() {
    fields.clear(), firsts.clear(), seconds.clear(), items.clear(), directions.clear();
    line = 0;
  }
};

struct Station {
  Fields fields;  // Name, Constraints, Type, Description
  Fields coord;   // XAxis, YAxis, Height, HemisphereZone
  std::size_t line = 0;
  void clear() { fields.clear(), coord.clear(), line = 0; }
};

class Reader final : public XmlHandler {
 public:
  Reader(std::string_view source, geodesy::Network& net, const NetworkReadOptions& o)
      : source_(source), net_(net), options_(o), builder_(net), geocentric_(net.ellipsoid) {}

  void parse(std::string_view text) {
    xml_.parse(text, source_, "E_DYNAML");
    if (!root_seen_) fail(1, "no <DnaXmlFormat> root element");
  }
  // A part of a file (read_dynaml): `pieces` are the file's prologue (its
  // root element's start tag), the part, and the root's end tag, as they
  // apply; `line_offset` maps their lines to the file's. The root's
  // warnings are the first part's to give.
  void parse_part(std::initializer_list<std::string_view> pieces, std::ptrdiff_t line_offset, bool root_warnings) {
    xml_.line_offset = line_offset;
    root_warnings_ = root_warnings;
    xml_.parse(pieces, source_, "E_DYNAML");
    if (!root_seen_) fail(1, "no <DnaXmlFormat> root element");
  }

  void start_element(const std::string& name, const XML_Char** attributes) override { start(name, attributes); }
  void end_element(const std::string& name) override { end(name); }
  void character_data(const char* s, std::size_t n) override { text_.append(s, n); }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, "E_DYNAML", source_ + ":" + std::to_string(line) + ": " + what);
  }
  std::size_t line() const { return xml_.line(); }
  std::string where(std::size_t at) const { return source_ + ":" + std::to_string(at); }

  void start(const std::string& name, const XML_Char** attributes) {
    text_.clear();
    const Tag tag = tag_of(name);
    const Tag parent = path_.empty() ? Tag::other : path_.back();
    path_.push_back(tag);
    if (path_.size() == 1) {
      if (name != "DnaXmlFormat") fail(line(), "root element <" + name + ">; expected <DnaXmlFormat>");
      root_seen_ = true;
      for (const XML_Char** a = attributes; *a; a += 2) {
        const std::string key = a[0], value = a[1];
        if (key == "referenceframe") frame_name_ = value;
        else if (key == "epoch") epoch_text_ = value;
        else if (key != "type" && key != "xmlns:xsi" && key != "xsi:noNamespaceSchemaLocation") {
          fail(line(), "<DnaXmlFormat> attribute " + key + "=\"" + value +
                           "\" is not read by geoanchor; expected type, referenceframe, epoch");
        }
      }
      if (root_warnings_ && (frame_name_.empty() || epoch_text_.empty())) {
        net_.warnings.push_back(source_ + ": <DnaXmlFormat> names no " +
                                std::string(frame_name_.empty() ? "referenceframe" : "epoch") +
                                ": DynaML.xsd's default (GDA2020, 01.01.2020) applies");
      }
      root_frame_ = frame_of(frame_name_.empty() ? "GDA2020" : frame_name_, epoch_text_.empty() ? "01.01.2020" : epoch_text_, line(),
                             "<DnaXmlFormat>");
      if (!net_.frame) {
        net_.frame = root_frame_;
        if (const auto e = geodesy::implied_ellipsoid(*root_frame_)) {
          net_.ellipsoid = *e;
          net_.ellipsoid_stated = true;
          geocentric_ = geodesy::GeocentricConverter(net_.ellipsoid);
        }
      }
      return;
    }
    if (path_.size() == 2) {
      // DynaML.xsd gives <DnaStation> and <DnaMeasurement> no attributes:
      // one would go unread (issue 40 point 10).
      if (*attributes && (tag == Tag::DnaStation || tag == Tag::DnaMeasurement)) {
        fail(line(), "<" + name + "> attribute " + std::string(attributes[0]) + "=\"" + attributes[1] +
                         "\" is not read by geoanchor (DynaML.xsd gives <" + name + "> no attributes)");
      }
      if (tag == Tag::DnaStation) {
        station_.clear();
        station_.line = line();
        in_station_ = true;
      } else if (tag == Tag::DnaMeasurement) {
        measurement_.clear();
        measurement_.line = line();
        in_measurement_ = true;
      } else {
        fail(line(), "element <" + name + "> in <DnaXmlFormat>; expected <DnaStation> or <DnaMeasurement>");
      }
      return;
    }
    // Every element where DynaML.xsd puts it, without attributes; anything
    // else is refused by name, never skipped.
    using Children = std::bitset<kTagCount>;
    static const std::array<std::optional<Children>, kTagCount> kChildren = [] {
      std::array<std::optional<Children>, kTagCount> c;
      const auto set = [&](Tag of, std::initializer_list<Tag> children) {
        Children b;
        for (Tag t : children) b.set(static_cast<std::size_t>(t));
        c[static_cast<std::size_t>(of)] = b;
      };
      using enum Tag;
      set(DnaStation, {Name, Constraints, Type, StationCoord, Description});
      set(StationCoord, {Name, XAxis, YAxis, Height, HemisphereZone});
      set(DnaMeasurement, {Type, Ignore, ReferenceFrame, Epoch, First, Second, Third, Value, StdDev, InstHeight, TargHeight, Total,
                           Directions, Vscale, Pscale, Lscale, Hscale, GPSBaseline, Clusterpoint, Coords, Source, MeasurementID,
                           ClusterID});
      set(GPSBaseline, {X, Y, Z, MeasurementID, SigmaXX, SigmaXY, SigmaXZ, SigmaYY, SigmaYZ, SigmaZZ, GPSCovariance});
      set(Clusterpoint, {X, Y, Z, MeasurementID, SigmaXX, SigmaXY, SigmaXZ, SigmaYY, SigmaYZ, SigmaZZ, PointCovariance});
      set(GPSCovariance, {m11, m12, m13, m21, m22, m23, m31, m32, m33});
      set(PointCovariance, {m11, m12, m13, m21, m22, m23, m31, m32, m33});
      set(Directions, {Ignore, Target, Value, StdDev, MeasurementID});
      return c;
    }();
    const auto& allowed = kChildren[static_cast<std::size_t>(parent)];
    if (!allowed) fail(line(), "element <" + name + "> inside <" + name_of(parent) + ">, which holds a value, not elements");
    if (!allowed->test(static_cast<std::size_t>(tag))) {
      std::set<std::string> names;  // in the order of their bytes
      for (std::size_t k = 0; k < kTagCount; ++k) {
        if (allowed->test(k)) names.insert(std::string(kTagNames[k]));
      }
      std::string list;
      for (const auto& k : names) list += (list.empty() ? "" : ", ") + k;
      fail(line(), "element <" + name + "> in <" + name_of(parent) + "> is not read by geoanchor; expected one of " + list);
    }
    if (*attributes) {
      fail(line(), "<" + name + "> attribute " + std::string(attributes[0]) + "=\"" + attributes[1] + "\" is not read by geoanchor");
    }
    if (in_measurement_ && tag == Tag::GPSBaseline) {
      Measurement& m = measurement_;
      Item& item = m.items.push();
      item.line = line();
      if (!m.firsts.empty()) item.first = m.firsts.back();
      if (!m.seconds.empty()) item.second = m.seconds.back();
    } else if (in_measurement_ && tag == Tag::Clusterpoint) {
      Measurement& m = measurement_;
      Item& item = m.items.push();
      item.line = line();
      if (!m.firsts.empty()) item.first = m.firsts.back();
    } else if (in_measurement_ && (tag == Tag::GPSCovariance || tag == Tag::PointCovariance)) {
      if (measurement_.items.empty()) fail(line(), "<" + name + "> outside a baseline or cluster point");
      measurement_.items.back().blocks.push();
    } else if (in_measurement_ && tag == Tag::Directions && path_.size() == 3) {
      measurement_.directions.push().line = line();
    }
  }

  void end(const std::string& name) {
    // The element's text, trimmed, viewed in text_ (cleared on the way out).
    struct ClearText {
      std::string& t;
      ~ClearText() { t.clear(); }
    } clear_text{text_};
    const std::string_view value = trim(text_);
    const std::size_t depth = path_.size();
    const Tag tag = path_.back();
    const Tag parent = depth >= 2 ? path_[depth - 2] : Tag::other;
    path_.pop_back();
    if (depth == 2) {
      if (tag == Tag::DnaStation) finish_station();
      if (tag == Tag::DnaMeasurement) finish_measurement();
      in_station_ = in_measurement_ = false;
      return;
    }
    // A value given twice is refused (First and Second repeat in clusters).
    auto put = [&](Fields& into) {
      if (!into.emplace(tag, value)) fail(line(), "<" + name + "> given twice in <" + name_of(parent) + ">");
    };
    using enum Tag;
    if (in_station_) {
      if (parent == DnaStation && tag != StationCoord) put(station_.fields);
      else if (parent == StationCoord) put(station_.coord);
      return;
    }
    if (!in_measurement_) return;
    Measurement& m = measurement_;
    if (parent == DnaMeasurement) {
      if (tag == First) m.firsts.push().assign(value);
      if (tag == Second) m.seconds.push().assign(value);
      if (tag != GPSBaseline && tag != Clusterpoint && tag != Directions) {
        if (tag == First || tag == Second) {
          m.fields.emplace(tag, value);  // the first one (clusters repeat them)
        } else {
          put(m.fields);
        }
      }
    } else if (parent == GPSBaseline || parent == Clusterpoint) {
      if (tag != GPSCovariance && tag != PointCovariance) put(m.items.back().fields);
    } else if (parent == GPSCovariance || parent == PointCovariance) {
      put(m.items.back().blocks.back());
    } else if (parent == Directions) {
      put(m.directions.back().fields);
    }
  }

  static std::string_view trim(std::string_view s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string_view::npos) return {};
    return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
  }

  geodesy::Frame frame_of(const std::string& name, const std::string& date, std::size_t at, const std::string& what) const {
    // dd.mm.yyyy
    int d = 0, mo = 0, y = 0;
    char dot1 = 0, dot2 = 0;
    std::istringstream in(date);
    in >> d >> dot1 >> mo >> dot2 >> y;
    const auto year = in && dot1 == '.' && dot2 == '.' ? geodesy::decimal_year_from_date(y, mo, d) : std::nullopt;
    if (!year) fail(at, what + " epoch '" + date + "': expected a date dd.mm.yyyy");
    return geodesy::Frame::parse(name + "@" + geodesy::format_decimal_year(*year), where(at) + ": " + what + " reference frame");
  }

  double number(const Fields& f, Tag key, std::size_t at, const std::string& what) const {
    const std::string* t = f.find(key);
    if (!t || t->empty()) fail(at, what + ": <" + name_of(key) + "> missing");
    const auto v = parse_finite_double(*t);
    if (!v) fail(at, what + ": <" + name_of(key) + "> '" + *t + "' is not a number");
    return *v;
  }
  const std::string& text(const Fields& f, Tag key) const {
    static const std::string kNone;
    const std::string* t = f.find(key);
    return t ? *t : kNone;
  }
  double positive_sigma(double v, std::size_t at, const std::string& what) const {
    if (!(v > 0.0)) fail(at, what + ": standard deviation " + format_shortest(v) + " must be > 0");
    return v;
  }

  // Orthometric height H to ellipsoidal at (lat, lon), when the geoid is there.
  std::optional<double> undulation(double lat_rad, double lon_rad, std::size_t at) const {
    if (!options_.geoid) return std::nullopt;
    return options_.geoid->undulation_m(geodesy::Angle::radians(lat_rad), geodesy::Angle::radians(lon_rad), where(at));
  }

  void finish_station() {
    const Station& s = station_;
    const std::string name = text(s.fields, Tag::Name);
    const std::string what = "station " + name;
    if (name.empty()) fail(s.line, "a <DnaStation> without a <Name>");
    std::string code = text(s.fields, Tag::Constraints);
    if (code.empty()) code = "FFF";
    if (code.size() != 3 || code.find_first_not_of("CFcf") != std::string::npos) {
      fail(s.line, what + ": <Constraints> '" + code + "': expected three letters C (constrained) or F (free)");
    }
    const std::string type = text(s.fields, Tag::Type);
    geodesy::StationConstraint c;
    Eigen::Vector3d position;
    bool orthometric = false;
    double lat = 0, lon = 0, height = number(s.coord, Tag::Height, s.line, what);
    if (type == "XYZ") {
      position = {number(s.coord, Tag::XAxis, s.line, what), number(s.coord, Tag::YAxis, s.line, what), height};
    } else if (type == "LLH" || type == "LLh") {
      lat = packed_dms_to_rad(text(s.coord, Tag::XAxis), where(s.line) + ": " + what + " <XAxis> (latitude)", net_.warnings);
      lon = packed_dms_to_rad(text(s.coord, Tag::YAxis), where(s.line) + ": " + what + " <YAxis> (longitude)", net_.warnings);
      if (!(std::fabs(lat) <= std::numbers::pi / 2.0)) {
        fail(s.line, what + ": latitude <XAxis> " + text(s.coord, Tag::XAxis) + " is not within ±90°");
      }
      if (!(std::fabs(lon) <= std::numbers::pi)) {
        fail(s.line, what + ": longitude <YAxis> " + text(s.coord, Tag::YAxis) + " is not within ±180°");
      }
      orthometric = type == "LLH";
    } else if (type == "UTM") {
      const std::string zone_text = text(s.coord, Tag::HemisphereZone);
      std::string zone = zone_text;
      if (!zone.empty() && std::isdigit(static_cast<unsigned char>(zone.back()))) {
        // DynaML writes the zone number alone; its frames (GDA94, GDA2020) are
        // Australia's, south of the equator. Elsewhere the hemisphere must be said.
        const std::string frame = net_.frame ? net_.frame->name() : "";
        if (frame.rfind("GDA", 0) != 0) {
          fail(s.line, what + ": <HemisphereZone> '" + zone_text + "' names no hemisphere and the frame " + frame +
                           " does not imply one; write it as " + zone_text + "N or " + zone_text + "S");
        }
        zone += "S";
      }
      const auto def = geodesy::utm_projection(net_.ellipsoid, geodesy::parse_utm_zone(zone, where(s.line) + ": " + what + " <HemisphereZone>"));
      const geodesy::TransverseMercator tm(def);
      geodesy::ProjectedPosition p;
      p.easting_m = number(s.coord, Tag::XAxis, s.line, what);
      p.northing_m = number(s.coord, Tag::YAxis, s.line, what);
      p.projection = def;
      const auto g = tm.try_inverse(p);
      if (!g) fail(s.line, what + ": easting/northing outside UTM zone " + zone);
      lat = g->lat.rad();
      lon = g->lon.rad();
      orthometric = true;
    } else {
      fail(s.line, what + ": <Type> '" + type + "': expected XYZ, LLH, LLh or UTM");
    }
    if (type != "XYZ") {
      double h = height;
      if (orthometric) {
        if (const auto n = undulation(lat, lon, s.line)) {
          h = height + *n;
        } else if (code[2] == 'C' || code[2] == 'c') {
          fail(s.line, what + ": its orthometric height is held (Constraints " + code +
                           ") and there is no geoid to make it ellipsoidal; give --geoid");
        } else {
          ++approximate_heights_;
        }
      }
      position = geocentric_.ecef_from_geodetic({geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), geodesy::EllipsoidalHeight{h}}).m;
    }
    // The letters' order: latitude, longitude, height for LLH; east, north,
    // up (or X, Y, Z) otherwise. geoanchor's order is latitude, longitude, height.
    for (std::size_t k = 0; k < 3; ++k) code[k] = static_cast<char>(std::toupper(static_cast<unsigned char>(code[k])));
    if (type == "XYZ" && code != "CCC" && code != "FFF") {
      fail(s.line, what + ": <Constraints> " + code + " holds some of X, Y, Z: geoanchor holds latitude, longitude and "
                       "height; give CCC, FFF or the station in LLh");
    }
    c.code = type == "LLH" || type == "XYZ" ? std::array<char, 3>{code[0], code[1], code[2]}
                                             : std::array<char, 3>{code[1], code[0], code[2]};
    builder_.define(name, position, c, where(s.line));
  }

  // A GNSS measurement's frame: its own ReferenceFrame/Epoch, else the file's.
  // The last one read is kept: a file's measurements mostly share theirs.
  geodesy::Frame measurement_frame(const Measurement& m) const {
    const std::string& f = text(m.fields, Tag::ReferenceFrame);
    const std::string& e = text(m.fields, Tag::Epoch);
    if (f.empty() && e.empty()) return *root_frame_;
    if (last_frame_ && f == last_frame_name_ && e == last_frame_epoch_) return *last_frame_;
    const geodesy::Frame frame = frame_of(f.empty() ? root_frame_->name() : f,
                                          e.empty() ? (epoch_text_.empty() ? "01.01.2020" : epoch_text_) : e, m.line, "measurement");
    last_frame_name_ = f;
    last_frame_epoch_ = e;
    last_frame_ = frame;
    return frame;
  }

  // The covariance of n GNSS items: diagonal blocks from Sigma*, cross blocks from the items' blocks.
  Eigen::MatrixXd gnss_covariance(const Measurement& m, const std::string& what) const {
    const std::size_t n = m.items.size();
    Eigen::MatrixXd v = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(3 * n), static_cast<Eigen::Index>(3 * n));
    using enum Tag;
    const Tag sig[3][3] = {{SigmaXX, SigmaXY, SigmaXZ}, {SigmaXY, SigmaYY, SigmaYZ}, {SigmaXZ, SigmaYZ, SigmaZZ}};
    for (std::size_t i = 0; i < n; ++i) {
      const Item& it = m.items[i];
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) v(static_cast<Eigen::Index>(3 * i) + r, static_cast<Eigen::Index>(3 * i) + c) = number(it.fields, sig[r][c], it.line, what);
      }
      if (it.blocks.size() != n - 1 - i) {
        fail(it.line, what + ": item " + std::to_string(i + 1) + " of " + std::to_string(n) + " carries " +
                          std::to_string(it.blocks.size()) + " covariance blocks; expected " + std::to_string(n - 1 - i) +
                          " (one with each later item)");
      }
      for (std::size_t k = 0; k < it.blocks.size(); ++k) {
        const std::size_t j = i + 1 + k;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            static constexpr Tag kBlock[3][3] = {{m11, m12, m13}, {m21, m22, m23}, {m31, m32, m33}};
            const double x = number(it.blocks[k], kBlock[r][c], it.line, what);
            v(static_cast<Eigen::Index>(3 * i) + r, static_cast<Eigen::Index>(3 * j) + c) = x;
            v(static_cast<Eigen::Index>(3 * j) + c, static_cast<Eigen::Index>(3 * i) + r) = x;
          }
        }
      }
    }
    return v;
  }

  void finish_measurement() {
    const Measurement& m = measurement_;
    const std::string type = text(m.fields, Tag::Type);
    const std::string what = "measurement " + type;
    geodesy::NetworkMeasurement x;
    x.source = where(m.line);
    x.ignore = !text(m.fields, Tag::Ignore).empty();
    auto station = [&](const std::string& id, const char* role) {
      if (id.empty()) fail(m.line, what + ": <" + std::string(role) + "> missing");
      return builder_.reference(id, x.source);
    };
    const std::string first = m.firsts.empty() ? "" : m.firsts.front();
    const std::string second = m.seconds.empty() ? "" : m.seconds.front();
    auto scalar = [&](MeasurementKind kind, double value, double sigma) {
      x.kind = kind;
      x.value = Eigen::VectorXd::Constant(1, value);
      x.covariance = Eigen::MatrixXd::Constant(1, 1, sigma * sigma);
    };
    // A packed sexagesimal <Value> of `kind`, within its range.
    auto angle = [&](MeasurementKind kind, const Fields& f, std::size_t at) {
      const std::string& written = text(f, Tag::Value);
      const std::string at_value = where(at) + ": " + what + " <Value>";
      const double v = packed_dms_to_rad(written, at_value, net_.warnings);
      check_angle_range(kind, v, written, AngleUnit::packed_dms, at_value);
      return v;
    };
    auto angle_sigma = [&](const Fields& f, std::size_t at) {
      return positive_sigma(number(f, Tag::StdDev, at, what), at, what) * kArcsec;
    };
    auto linear_sigma = [&]() { return positive_sigma(number(m.fields, Tag::StdDev, m.line, what), m.line, what); };
    auto heights = [&]() {
      if (m.fields.count(Tag::InstHeight) && !text(m.fields, Tag::InstHeight).empty()) x.instrument_height_m = number(m.fields, Tag::InstHeight, m.line, what);
      if (m.fields.count(Tag::TargHeight) && !text(m.fields, Tag::TargHeight).empty()) x.target_height_m = number(m.fields, Tag::TargHeight, m.line, what);
    };
    if (type.size() != 1) fail(m.line, "<Type> '" + type + "': expected one letter (A, B, C, D, E, G, H, I, J, K, L, P, Q, R, S, V, X, Y, Z)");
    switch (type[0]) {
      case 'G':
      case 'X': {
        if (m.items.empty()) fail(m.line, what + ": no <GPSBaseline>");
        if (type[0] == 'X' && !text(m.fields, Tag::Total).empty() &&
            number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.items.size())) {
          fail(m.line, what + ": <Total> " + text(m.fields, Tag::Total) + " but " + std::to_string(m.items.size()) + " <GPSBaseline>");
        }
        x.kind = MeasurementKind::gnss_baselines;
        x.value.resize(static_cast<Eigen::Index>(3 * m.items.size()));
        for (std::size_t i = 0; i < m.items.size(); ++i) {
          const Item& it = m.items[i];
          const std::string a = type[0] == 'G' ? first : it.first, b = type[0] == 'G' ? second : it.second;
          x.stations.push_back(station(a, "First"));
          x.stations.push_back(station(b, "Second"));
          x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) =
              Eigen::Vector3d(number(it.fields, Tag::X, it.line, what), number(it.fields, Tag::Y, it.line, what), number(it.fields, Tag::Z, it.line, what));
        }
        x.covariance = gnss_covariance(m, what);
        x.frame = measurement_frame(m);
        scale(x, m, what);
        break;
      }
      case 'Y': {
        if (m.items.empty()) fail(m.line, what + ": no <Clusterpoint>");
        if (!text(m.fields, Tag::Total).empty() && number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.items.size())) {
          fail(m.line, what + ": <Total> " + text(m.fields, Tag::Total) + " but " + std::to_string(m.items.size()) + " <Clusterpoint>");
        }
        const std::string coords = text(m.fields, Tag::Coords);
        if (coords != "XYZ" && coords != "LLH") fail(m.line, what + ": <Coords> '" + coords + "': expected XYZ or LLH");
        x.kind = MeasurementKind::gnss_points;
        const std::size_t n = m.items.size();
        x.value.resize(static_cast<Eigen::Index>(3 * n));
        Eigen::MatrixXd v = gnss_covariance(m, what);
        Eigen::MatrixXd j = Eigen::MatrixXd::Identity(v.rows(), v.cols());
        for (std::size_t i = 0; i < n; ++i) {
          const Item& it = m.items[i];
          x.stations.push_back(station(it.first, "First"));
          if (coords == "XYZ") {
            x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) =
                Eigen::Vector3d(number(it.fields, Tag::X, it.line, what), number(it.fields, Tag::Y, it.line, what), number(it.fields, Tag::Z, it.line, what));
            continue;
          }
          // LLH: latitude and longitude (packed), orthometric height; the
          // covariance in (latitude rad, longitude rad, height m).
          const std::string at_lat = where(it.line) + ": " + what + " <X> (latitude)";
          const std::string at_lon = where(it.line) + ": " + what + " <Y> (longitude)";
          const double lat = packed_dms_to_rad(text(it.fields, Tag::X), at_lat, net_.warnings);
          const double lon = packed_dms_to_rad(text(it.fields, Tag::Y), at_lon, net_.warnings);
          check_angle_range(MeasurementKind::geodetic_latitude, lat, text(it.fields, Tag::X), AngleUnit::packed_dms, at_lat);
          check_angle_range(MeasurementKind::geodetic_longitude, lon, text(it.fields, Tag::Y), AngleUnit::packed_dms, at_lon);
          const auto n_m = undulation(lat, lon, it.line);
          if (!n_m) fail(it.line, what + ": a point cluster of orthometric heights (Coords LLH) needs the geoid: give --geoid");
          const double h = number(it.fields, Tag::Z, it.line, what) + *n_m;
          const geodesy::GeodeticPosition g{geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), geodesy::EllipsoidalHeight{h}};
          x.value.segment<3>(static_cast<Eigen::Index>(3 * i)) = geocentric_.ecef_from_geodetic(g).m;
          // ∂(X, Y, Z) / ∂(φ, λ, h): north·(M + h), east·(N + h)·cos φ, up.
          const double e2 = net_.ellipsoid.e2(), a = net_.ellipsoid.a_m();
          const double w = std::sqrt(1.0 - e2 * std::sin(lat) * std::sin(lat));
          const double meridian = a * (1.0 - e2) / (w * w * w), prime = a / w;
          const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
          Eigen::Matrix3d jac;
          jac.col(0) = r.row(1).transpose() * (meridian + h);
          jac.col(1) = r.row(0).transpose() * (prime + h) * std::cos(lat);
          jac.col(2) = r.row(2).transpose();
          j.block<3, 3>(static_cast<Eigen::Index>(3 * i), static_cast<Eigen::Index>(3 * i)) = jac;
        }
        x.covariance = j * v * j.transpose();
        x.frame = measurement_frame(m);
        scale(x, m, what);
        break;
      }
      case 'S':
      case 'E':
      case 'C': {
        const bool slope = type[0] == 'S';
        scalar(slope ? MeasurementKind::slope_distance : type[0] == 'E' ? MeasurementKind::ellipsoid_arc : MeasurementKind::chord_distance,
               number(m.fields, Tag::Value, m.line, what), linear_sigma());
        x.stations = {station(first, "First"), station(second, "Second")};
        if (slope) heights();
        break;
      }
      case 'A': {
        scalar(MeasurementKind::horizontal_angle, angle(MeasurementKind::horizontal_angle, m.fields, m.line),
               angle_sigma(m.fields, m.line));
        x.stations = {station(first, "First"), station(second, "Second"), station(text(m.fields, Tag::Third), "Third")};
        break;
      }
      case 'B':
      case 'K': {
        // K, an astronomic azimuth, is read as geodetic: the deflections of
        // the vertical are taken as zero (docs/commands/adjust.md).
        scalar(MeasurementKind::azimuth, angle(MeasurementKind::azimuth, m.fields, m.line), angle_sigma(m.fields, m.line));
        x.stations = {station(first, "First"), station(second, "Second")};
        break;
      }
      case 'V':
      case 'Z': {
        const MeasurementKind kind = type[0] == 'V' ? MeasurementKind::zenith_angle : MeasurementKind::vertical_angle;
        scalar(kind, angle(kind, m.fields, m.line), angle_sigma(m.fields, m.line));
        x.stations = {station(first, "First"), station(second, "Second")};
        heights();
        break;
      }
      case 'H':
      case 'R': {
        scalar(type[0] == 'H' ? MeasurementKind::orthometric_height : MeasurementKind::ellipsoidal_height,
               number(m.fields, Tag::Value, m.line, what), linear_sigma());
        x.stations = {station(first, "First")};
        break;
      }
      case 'L': {
        scalar(MeasurementKind::height_difference, number(m.fields, Tag::Value, m.line, what), linear_sigma());
        x.stations = {station(first, "First"), station(second, "Second")};
        break;
      }
      case 'P':
      case 'Q':
      case 'I':
      case 'J': {
        // I and J, astronomic, are read as geodetic (deflections zero).
        const MeasurementKind kind =
            type[0] == 'P' || type[0] == 'I' ? MeasurementKind::geodetic_latitude : MeasurementKind::geodetic_longitude;
        scalar(kind, angle(kind, m.fields, m.line), angle_sigma(m.fields, m.line));
        x.stations = {station(first, "First")};
        break;
      }
      case 'D': {
        const std::size_t at = station(first, "First");
        const std::size_t set = net_.direction_sets.size();
        net_.direction_sets.push_back({at, where(m.line)});
        const bool ignored = x.ignore;
        // The reference object, then the other targets.
        geodesy::NetworkMeasurement ro;
        ro.source = where(m.line);
        ro.kind = MeasurementKind::direction;
        ro.stations = {at, station(second, "Second")};
        const double s = angle_sigma(m.fields, m.line);
        ro.value = Eigen::VectorXd::Constant(1, angle(MeasurementKind::direction, m.fields, m.line));
        ro.covariance = Eigen::MatrixXd::Constant(1, 1, s * s);
        ro.set = set;
        ro.ignore = ignored;
        net_.measurements.push_back(ro);
        if (!text(m.fields, Tag::Total).empty() &&
            number(m.fields, Tag::Total, m.line, what) != static_cast<double>(m.directions.size())) {
          fail(m.line, what + ": <Total> " + text(m.fields, Tag::Total) + " but " + std::to_string(m.directions.size()) + " <Directions>");
        }
        for (const auto& d : m.directions) {
          geodesy::NetworkMeasurement dir = ro;
          dir.source = where(d.line);
          dir.stations = {at, station(text(d.fields, Tag::Target), "Target")};
          const double sd = angle_sigma(d.fields, d.line);
          dir.value = Eigen::VectorXd::Constant(1, angle(MeasurementKind::direction, d.fields, d.line));
          dir.covariance = Eigen::MatrixXd::Constant(1, 1, sd * sd);
          dir.ignore = ignored || !text(d.fields, Tag::Ignore).empty();
          net_.measurements.push_back(dir);
        }
        return;
      }
      case 'M':
        fail(m.line, what + ": an MSL arc is not read by geoanchor (give it as an ellipsoid arc, type E)");
      default:
        fail(m.line, "<Type> '" + type + "': expected one of A, B, C, D, E, G, H, I, J, K, L, P, Q, R, S, V, X, Y, Z");
    }
    net_.measurements.push_back(std::move(x));
  }

  // Vscale multiplies the whole covariance; Pscale, Lscale, Hscale the
  // variances along latitude (north), longitude (east) and height (up),
  // applied when the stations are known (Network measurement's
  // local_variance_scale).
  void scale(geodesy::NetworkMeasurement& x, const Measurement& m, const std::string& what) const {
    auto factor = [&](Tag key) {
      const std::string& t = text(m.fields, key);
      if (t.empty()) return 1.0;
      const auto v = parse_finite_double(t);
      if (!v || !(*v > 0.0)) fail(m.line, what + ": <" + name_of(key) + "> '" + t + "': expected a factor > 0");
      return *v;
    };
    x.covariance *= factor(Tag::Vscale);
    x.local_variance_scale = Eigen::Vector3d(factor(Tag::Pscale), factor(Tag::Lscale), factor(Tag::Hscale));
  }

 public:
  std::size_t approximate_heights() const { return approximate_heights_; }

 private:
  std::string source_;
  geodesy::Network& net_;
  const NetworkReadOptions& options_;
  NetworkBuilder builder_;
  geodesy::GeocentricConverter geocentric_;
  XmlStream xml_{*this};
  std::vector<Tag> path_;
  std::string text_;
  bool root_seen_ = false, root_warnings_ = true;
  std::string frame_name_, epoch_text_;
  std::optional<geodesy::Frame> root_frame_;
  // The element being read, kept from one to the next (Reused, Fields).
  Station station_;
  Measurement measurement_;
  bool in_station_ = false, in_measurement_ = false;
  mutable std::string last_frame_name_, last_frame_epoch_;
  mutable std::optional<geodesy::Frame> last_frame_;
  std::size_t approximate_heights_ = 0;
};

}  // namespace

namespace {

void warn_approximate_heights(std::string_view source, std::size_t count, geodesy::Network& into) {
  if (count == 0) return;
  into.warnings.push_back(std::string(source) + ": " + std::to_string(count) +
                          " free station(s) have orthometric heights and there is no --geoid: each starts the iteration "
                          "at h = H (metres off where N is metres; their adjusted heights do not depend on it)");
}

// The line breaks in `t` as expat counts them (XML's end-of-line rule): LF,
// CR LF and a CR alone are one each. A part's line offset counted in LFs
// alone put every line after a lone CR elsewhere than one reading does.
std::ptrdiff_t xml_line_breaks(std::string_view t) {
  std::ptrdiff_t n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] == '\n' || (t[i] == '\r' && (i + 1 == t.size() || t[i + 1] != '\n'))) ++n;
  }
  return n;
}

// A large file read in parts on threads (expat is one thread; a 10⁵-station
// measurement file is 180 MB of XML). The parts are cut where a top-level
// element (<DnaStation>, <DnaMeasurement>) starts; each is read as a
// document of its own (the file's prologue and root start tag before it,
// the root's end tag after it) into a network of its own, and the networks
// are joined in the file's order by station name: the same network as one
// reading. A cut that fell inside a comment or CDATA section leaves a part
// that is not well-formed; then, or on any other error, nothing of the
// parts is kept and the caller reads the file whole, which reports the
// error as it always does. False: not read here.
bool read_dynaml_in_parts(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  if (options.geoid) return false;  // (PROJ's grids are for one thread)
  const std::size_t cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t wanted = std::min<std::size_t>(cores, options.dynaml_part_bytes ? text.size() / options.dynaml_part_bytes : 1);
  if (wanted < 2) return false;
  // The root element's start tag (past the prologue; attribute values may
  // hold '>', quotes not).
  const std::size_t root = text.find("<DnaXmlFormat");
  if (root == std::string_view::npos || text.substr(0, root).find("<!DOCTYPE") != std::string_view::npos) return false;
  std::size_t root_end = root;
  char quote = 0;
  for (; root_end < text.size(); ++root_end) {
    const char c = text[root_end];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '>') {
      break;
    }
  }
  if (root_end >= text.size() || text[root_end - 1] == '/') return false;
  ++root_end;
  const std::string_view prologue = text.substr(0, root_end);
  // The cuts: at the first top-level element at or past each share.
  std::vector<std::size_t> cut{root_end};
  for (std::size_t k = 1; k < wanted; ++k) {
    std::size_t at = std::max(cut.back() + 1, root_end + k * (text.size() - root_end) / wanted);
    for (at = text.find("<Dna", at); at != std::string_view::npos; at = text.find("<Dna", at + 1)) {
      const std::string_view rest = text.substr(at + 4);
      if (rest.substr(0, 12) == "Measurement>" || rest.substr(0, 8) == "Station>") break;
    }
    if (at == std::string_view::npos) break;
    cut.push_back(at);
  }
  cut.push_back(text.size());
  const std::size_t parts = cut.size() - 1;
  if (parts < 2) return false;
  const std::ptrdiff_t prologue_lines = xml_line_breaks(prologue);
  std::vector<std::ptrdiff_t> line_before(parts, 0);  // line breaks before each part
  for (std::size_t k = 1; k < parts; ++k) {
    const std::size_t from = k == 1 ? 0 : cut[k - 1];
    line_before[k] = line_before[k - 1] + xml_line_breaks(text.substr(from, cut[k] - from));
  }
  struct Part {
    geodesy::Network net;
    std::size_t approximate_heights = 0;
    bool ok = false;
  };
  std::vector<Part> read(parts);
  const auto read_part = [&](std::size_t k) {
    Part& part = read[k];
    part.net.space = geodesy::NetworkSpace::ellipsoidal;
    part.net.frame = into.frame;
    part.net.ellipsoid = into.ellipsoid;
    part.net.ellipsoid_stated = into.ellipsoid_stated;
    try {
      Reader reader(source, part.net, options);
      constexpr std::string_view kEnd = "</DnaXmlFormat>";
      const std::string_view body = text.substr(cut[k], cut[k + 1] - cut[k]);
      // Room for its measurements at once (a few hundred bytes each, moved
      // again at every doubling otherwise): one per <DnaMeasurement>, a
      // hint (a direction set is several).
      {
        const std::string_view own = k == 0 ? text.substr(0, cut[1]) : body;
        std::size_t count = 0;
        for (auto at = own.find("<DnaMeasurement"); at != std::string_view::npos; at = own.find("<DnaMeasurement", at + 1)) ++count;
        part.net.measurements.reserve(count);
      }
      if (k == 0) {
        reader.parse_part({text.substr(0, cut[1]), kEnd}, 0, true);
      } else if (k + 1 < parts) {
        reader.parse_part({prologue, body, kEnd}, line_before[k] - prologue_lines, false);
      } else {
        reader.parse_part({prologue, body}, line_before[k] - prologue_lines, false);
      }
      part.approximate_heights = reader.approximate_heights();
      part.ok = true;
    } catch (...) {
      part.ok = false;  // read whole instead, for the error as it is reported there
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(parts);
  for (std::size_t k = 1; k < parts; ++k) {
    try {
      pool.emplace_back(read_part, k);
    } catch (...) {  // std::system_error, std::bad_alloc: never unwind past running threads
      read_part(k);
    }
  }
  read_part(0);
  for (auto& t : pool) t.join();
  if (!std::all_of(read.begin(), read.end(), [](const Part& p) { return p.ok; })) return false;

  // Joined in order: each part's stations by name (defined or referenced,
  // in the order they came), then its measurements and direction sets.
  geodesy::Network joined = into;
  try {
    NetworkBuilder builder(joined);
    std::size_t approximate = 0, measurements = joined.measurements.size();
    for (std::size_t k = 0; k < parts; ++k) measurements += read[k].net.measurements.size();
    joined.measurements.reserve(measurements);  // moved in once, not again at each doubling
    for (std::size_t k = 0; k < parts; ++k) {
      Part& part = read[k];
      if (k == 0 && !joined.frame) {
        joined.frame = part.net.frame;
        joined.ellipsoid = part.net.ellipsoid;
        joined.ellipsoid_stated = part.net.ellipsoid_stated;
      }
      std::vector<std::size_t> station(part.net.stations.size());
      for (std::size_t i = 0; i < part.net.stations.size(); ++i) {
        const geodesy::NetworkStation& s = part.net.stations[i];
        station[i] = s.defined ? builder.define(s.id, s.position, s.constraint, s.source) : builder.reference(s.id, s.source);
      }
      const std::size_t sets = joined.direction_sets.size();
      for (auto d : part.net.direction_sets) {
        d.station = station[d.station];
        joined.direction_sets.push_back(std::move(d));
      }
      for (auto& m : part.net.measurements) {
        for (auto& st : m.stations) st = station[st];
        if (m.set) *m.set += sets;
        joined.measurements.push_back(std::move(m));
      }
      joined.warnings.insert(joined.warnings.end(), part.net.warnings.begin(), part.net.warnings.end());
      approximate += part.approximate_heights;
    }
    warn_approximate_heights(source, approximate, joined);
  } catch (const Error&) {
    return false;  // (a station defined twice, differently: read whole, for the message as it is)
  }
  into = std::move(joined);
  return true;
}

}  // namespace

void read_dynaml(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  if (!into.stations.empty() && into.space != geodesy::NetworkSpace::ellipsoidal) {
    throw Error(ErrorKind::input, "E_NETWORK", std::string(source) + ": DynaML is a network on the ellipsoid; the other inputs are local");
  }
  into.space = geodesy::NetworkSpace::ellipsoidal;
  if (read_dynaml_in_parts(text, source, into, options)) return;
  Reader reader(source, into, options);
  reader.parse(text);
  warn_approximate_heights(source, reader.approximate_heights(), into);
}

}  // namespace geoanchor::io::detail
