#pragma once
// The DynaML reader (private to io): an expat handler that keeps one
// station's or measurement's elements at a time and turns each, when it
// ends, into the network (network_dynaml.cpp reads a file with it).

#include <Eigen/Core>

#include <array>
#include <bitset>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "network/network_builder.hpp"
#include "xml_stream.hpp"

namespace geoanchor::io::detail::dynaml {

inline constexpr double kArcsec = std::numbers::pi / 648000.0;

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
inline constexpr std::array<std::string_view, kTagCount> kTagNames = {
    "",
    "DnaXmlFormat", "DnaStation", "DnaMeasurement", "Name", "Constraints", "Type", "StationCoord", "Description",
    "XAxis", "YAxis", "Height", "HemisphereZone", "Ignore", "ReferenceFrame", "Epoch", "First", "Second",
    "Third", "Value", "StdDev", "InstHeight", "TargHeight", "Total", "Directions", "Vscale", "Pscale", "Lscale",
    "Hscale", "GPSBaseline", "Clusterpoint", "Coords", "Source", "MeasurementID", "ClusterID", "X", "Y", "Z",
    "SigmaXX", "SigmaXY", "SigmaXZ", "SigmaYY", "SigmaYZ", "SigmaZZ", "GPSCovariance", "PointCovariance", "m11",
    "m12", "m13", "m21", "m22", "m23", "m31", "m32", "m33", "Target"
};

inline Tag tag_of(std::string_view name) {
  static const std::unordered_map<std::string_view, Tag> kByName = [] {
    std::unordered_map<std::string_view, Tag> m;
    for (std::size_t k = 1; k < kTagCount; ++k) m.emplace(kTagNames[k], static_cast<Tag>(k));
    return m;
  }();
  const auto it = kByName.find(name);
  return it == kByName.end() ? Tag::other : it->second;
}
inline std::string name_of(Tag t) { return std::string(kTagNames[static_cast<std::size_t>(t)]); }

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

// The measurement being finished (Reader::finish_measurement): its element,
// its type and its name in messages, its stations' names, and what it
// becomes.
struct Finishing {
  const Measurement& m;
  const std::string& type;
  const std::string& what;
  geodesy::NetworkMeasurement& x;
  const std::string& first;
  const std::string& second;
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

  // DynAdjust's DNA text (network_dna.cpp): the same records read from
  // fixed columns, finished as DynaML's elements are, so that a network
  // reads the same from either form. `labels` name each field (and its
  // columns) in messages; the header's frame and epoch are the root's.
  using Labels = std::array<std::string, kTagCount>;
  void begin_dna(const Labels& labels, const std::string& frame, const std::string& epoch, std::size_t header_line) {
    dna_ = &labels;
    root_seen_ = true;
    set_root(frame, epoch, header_line, "the DNA header");
  }
  Station& dna_station(std::size_t at) {
    station_.clear();
    station_.line = at;
    return station_;
  }
  Measurement& dna_measurement(std::size_t at) {
    measurement_.clear();
    measurement_.line = at;
    return measurement_;
  }
  void finish_dna_station() { finish_station(); }
  void finish_dna_measurement() { finish_measurement(); }

  void start_element(const std::string& name, const XML_Char** attributes) override { start(name, attributes); }
  void end_element(const std::string& name) override { end(name); }
  void character_data(const char* s, std::size_t n) override { text_.append(s, n); }

 private:
  [[noreturn]] void fail(std::size_t line, const std::string& what) const {
    throw Error(ErrorKind::input, dna_ ? "E_DNA" : "E_DYNAML", source_ + ":" + std::to_string(line) + ": " + what);
  }
  // A field in messages: DynaML's element (<Value>), or DNA text's field
  // and columns (dna_labels).
  std::string field(Tag t) const { return dna_ ? (*dna_)[static_cast<std::size_t>(t)] : "<" + name_of(t) + ">"; }
  std::size_t line() const { return xml_.line(); }
  std::string where(std::size_t at) const { return source_ + ":" + std::to_string(at); }

  // Elements and their text (network_dynaml_elements.cpp).
  void start(const std::string& name, const XML_Char** attributes);
  void end(const std::string& name);

  static std::string_view trim(std::string_view s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string_view::npos) return {};
    return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
  }

  // The file's frame and epoch (DynaML's root attributes, DNA's header):
  // DynaML.xsd's defaults when not given, with a warning; the network's
  // frame and ellipsoid when it has none yet (network_dynaml_elements.cpp).
  void set_root(const std::string& frame_name, const std::string& epoch_text, std::size_t at, const std::string& what);

  // A frame at a DynaML date dd.mm.yyyy (network_dynaml_stations.cpp).
  geodesy::Frame frame_of(const std::string& name, const std::string& date, std::size_t at, const std::string& what) const;

  double number(const Fields& f, Tag key, std::size_t at, const std::string& what) const {
    const std::string* t = f.find(key);
    if (!t || t->empty()) fail(at, what + ": " + field(key) + " missing");
    const auto v = parse_finite_double(*t);
    if (!v) fail(at, what + ": " + field(key) + " '" + *t + "' is not a number");
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

  // Orthometric height H to ellipsoidal at station `name` (lat, lon): the
  // per-station geoid file's N, else the grid's, when there is one.
  std::optional<double> undulation(const std::string& name, double lat_rad, double lon_rad, std::size_t at) const {
    if (options_.station_geoid) {
      if (const auto it = options_.station_geoid->by_station.find(name); it != options_.station_geoid->by_station.end()) {
        return it->second.n_m;
      }
    }
    if (!options_.geoid) return std::nullopt;
    return options_.geoid->undulation_m(geodesy::Angle::radians(lat_rad), geodesy::Angle::radians(lon_rad), where(at));
  }

  // A station into the network (network_dynaml_stations.cpp).
  void finish_station();

  // A measurement into the network, and its steps (network_dynaml_measurements.cpp).
  geodesy::Frame measurement_frame(const Measurement& m) const;
  Eigen::MatrixXd gnss_covariance(const Measurement& m, const std::string& what) const;
  void finish_measurement();
  std::size_t station(const Finishing& fin, const std::string& id, const char* role);
  static void scalar(const Finishing& fin, geodesy::MeasurementKind kind, double value, double sigma);
  double angle(const Finishing& fin, geodesy::MeasurementKind kind, const Fields& f, std::size_t at) const;
  double angle_sigma(const Finishing& fin, const Fields& f, std::size_t at) const;
  double linear_sigma(const Finishing& fin) const;
  void heights(const Finishing& fin) const;
  void gnss_baselines(const Finishing& fin);
  void gnss_points(const Finishing& fin);
  void direction_set(const Finishing& fin);
  void scale(geodesy::NetworkMeasurement& x, const Measurement& m, const std::string& what) const;

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
  const Labels* dna_ = nullptr;  // reading DNA text (begin_dna)
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

// The warning for free stations whose orthometric heights start the
// iteration without a geoid (network_dynaml.cpp).
void warn_approximate_heights(std::string_view source, std::size_t count, geodesy::Network& into);
// DynaML and DNA networks are on the ellipsoid: refused beside local inputs.
void require_ellipsoidal(std::string_view source, const char* format, geodesy::Network& into);

}  // namespace geoanchor::io::detail::dynaml
