// STAR*NET data files (.dat), read into a local network.
//
// The format as the STAR*NET V6 reference manual (Starplus Software, 2004)
// defines it in chapter 5, "Preparing Input Data" (docs/network-format.md
// lists what is read, the mapping and what is refused):
//  - one record a line: a code, the station names joined by the separator
//    ('-'), the values, their standard errors, an optional HI/HT; '#'
//    starts a comment, "'" the descriptor (5.5);
//  - C (coordinates), E (elevation) with fixity '!' (fixed) and '*' (free)
//    or standard errors (5.6, coordinate data types);
//  - A, D, V, B (single observations), M, BM, DV (multiple observations),
//    DB/DN/DM/DE (direction sets), L (differential levelling) (5.6);
//  - inline options .2D/.3D, .UNITS, .ORDER, .DELTA, .SEPARATOR,
//    .INCLUDE, .ELEVATION (5.9; network_starnet_options.cpp).
// C coordinates are plane coordinates: the network is local, x north, y
// east, angles clockwise (GNU Gama's axes "ne", left-handed). P/PH geodetic
// positions, EH ellipsoid heights and G1-G3 GPS vectors (the STAR*NET-PRO
// supplement) make the file's stations part of an ellipsoidal network,
// on the frame and ellipsoid of an input read before it (a STAR*NET data
// file names no datum); C lines are refused there.

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/utf8.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/io/network/network_input.hpp"
#include "network/network_builder.hpp"
#include "network/network_readers.hpp"
#include "network/network_starnet.hpp"

namespace geoanchor::io::detail {
namespace {

using geodesy::MeasurementKind;
using starnet::fail;
using starnet::Settings;
using Words = std::vector<std::string_view>;

// .INCLUDE nesting beyond this is refused (a cycle is refused at once).
constexpr int kMaxIncludeDepth = 16;

// A station's C (or P) and E lines, defined once every line is read.
struct StationText {
  // north (x), east (y), elevation (z), metres; P/PH: latitude, longitude
  // (radians, east positive), elevation
  std::array<std::optional<double>, 3> value;
  bool ellipsoid_height = false;  // the elevation is an ellipsoid height (PH, EH, .ELEVATION Ellipsoidal)
  geodesy::StationConstraint constraint;
  std::string where;            // its C, P (or E) line
  std::string elevation_where;  // its E line
};

// A GPS vector while its G1, G2, G3 lines are read.
struct PendingVector {
  std::size_t from = 0, to = 0;
  Eigen::Vector3d delta = Eigen::Vector3d::Zero();
  std::string where, name;               // its G1 line; its G0 text
  std::vector<std::string> g2;           // its G2 line's words
  std::string g2_where;
};

// One observation of a data line before its standard error is known.
struct Obs {
  MeasurementKind kind;
  std::vector<std::size_t> stations;
  double value = 0.0;
  bool vertical = false;  // the vertical (zenith or elevation difference) of a 3D line: takes the HI/HT
};

class Reader {
 public:
  Reader(geodesy::Network& net, const NetworkReadOptions& options) : net_(net), options_(options), builder_(net) {}

  void read(std::string_view text, const std::string& source, int depth, std::vector<std::filesystem::path>& stack) {
    std::size_t at = 0, number = 0;
    if (text.substr(0, 3) == "\xEF\xBB\xBF") at = 3;
    while (at < text.size()) {
      // Lines end at LF, CR LF or a lone CR (RELIABILITY 44).
      std::size_t end = text.find_first_of("\r\n", at);
      if (end == std::string_view::npos) end = text.size();
      const std::string_view line = text.substr(at, end - at);
      at = end;
      if (at < text.size() && text[at] == '\r') ++at;
      if (at < text.size() && text[at] == '\n') ++at;
      ++number;
      const Words w = starnet::words(line);
      if (w.empty()) continue;
      const std::string where = source + ":" + std::to_string(number);
      if (w[0][0] == '.') {
        const std::string was = settings_.refraction_where;
        const std::string include = starnet::apply_inline_option(w, settings_, where);
        if (!include.empty()) read_include(include, source, where, depth, stack);
        else if (settings_.refraction_where != was) refraction(where);
        continue;
      }
      line_ = line;
      record(w, where);
    }
    if (gps_) fail(gps_->where, "G1 without its " + std::string(gps_->g2.empty() ? "G2 and G3" : "G3") + " lines (the file ends)");
    if (depth == 0 && set_) fail(set_where_, "a direction set (DB) without its DE");
  }

  void finish() {
    if (net_.refraction_k && !zenith_where_.empty()) {
      fail(zenith_where_, "a zenith angle before any .REFRACTION, read with STAR*NET's project coefficient (not in the data file), "
                          "while " + net_.refraction_source + " gives the network's coefficient: put .REFRACTION before it");
    }
    // A file of observations alone after an ellipsoidal network joins it.
    if (geodetic_where_.empty() && plane_where_.empty() && before_stations_ > 0 && net_.space == geodesy::NetworkSpace::ellipsoidal &&
        net_.frame && !first_where_.empty()) {
      geodetic_where_ = first_where_;
    }
    if (!geodetic_where_.empty()) return finish_geodetic();
    if (net_.refraction_k && *net_.refraction_k != 0.0) {
      fail(net_.refraction_source, ".REFRACTION " + format_shortest(*net_.refraction_k) + " in a local network: geoanchor's local "
                                   "model is a plane, without curvature or refraction; give .REFRACTION 0 or none");
    }
    const int dims = uses3d_ ? 3 : uses2d_ ? 2 : 1;
    const bool first = before_stations_ == 0 && before_measurements_ == 0;
    if (!first && net_.space != geodesy::NetworkSpace::local) {
      fail(first_where_, "a local network (STAR*NET C coordinates), but the other inputs are on the ellipsoid");
    }
    if (!first && (net_.axes.x != 'n' || net_.axes.y != 'e' || !net_.axes.angles_clockwise)) {
      fail(first_where_, "STAR*NET's axes (x north, y east, clockwise) differ from another input's (" + net_.axes.name() + ")");
    }
    net_.space = geodesy::NetworkSpace::local;
    net_.axes = geodesy::LocalAxes{};
    net_.local_dimensions = first || net_.local_dimensions == dims ? dims : 3;
    for (const auto& id : order_) define(id, stations_.at(id), dims);
    // Stations only measured: placed by the adjustment from the measurements.
    for (std::size_t i = before_stations_; i < net_.stations.size(); ++i) {
      geodesy::NetworkStation& s = net_.stations[i];
      if (s.defined) continue;
      builder_.define(s.id, Eigen::Vector3d::Zero(), {}, s.source);
      net_.stations[i].position_known = false;
    }
  }

  void start() {
    before_stations_ = net_.stations.size();
    before_measurements_ = net_.measurements.size();
  }

 private:
  void read_include(const std::string& name, const std::string& source, const std::string& where, int depth,
                    std::vector<std::filesystem::path>& stack) {
    if (source == "standard input") fail(where, ".INCLUDE " + name + " in standard input: give the data file by its path");
    if (depth + 1 > kMaxIncludeDepth) fail(where, ".INCLUDE " + name + ": more than " + std::to_string(kMaxIncludeDepth) + " files deep");
    const std::filesystem::path path = std::filesystem::path(source).parent_path() / name;
    std::error_code ec;
    const std::filesystem::path canonical = std::filesystem::weakly_canonical(path, ec);
    for (const auto& p : stack) {
      if (!ec && p == canonical) fail(where, ".INCLUDE " + name + ": " + path.string() + " includes itself (an include cycle)");
    }
    if (!std::filesystem::is_regular_file(path, ec)) {
      throw Error(ErrorKind::io, "E_READ", where + ": .INCLUDE " + name + ": " + path.string() + " is not a regular file");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(ErrorKind::io, "E_READ", where + ": .INCLUDE " + name + ": " + path.string() + " cannot be read");
    std::ostringstream s;
    s << in.rdbuf();
    const std::string text = s.str();
    if (const auto bad = first_invalid_utf8(text)) {
      fail(path.string(), "byte " + std::to_string(*bad) + " is not UTF-8; geoanchor reads UTF-8 text");
    }
    stack.push_back(canonical);
    read(text, path.string(), depth + 1, stack);
    stack.pop_back();
  }

  std::size_t station(std::string_view name, const std::string& where) {
    if (first_where_.empty()) first_where_ = where;
    return builder_.reference(std::string(name), where);
  }

  // The station names of w[1], `count` of them, split at the separator.
  std::vector<std::string_view> names(const Words& w, std::size_t count, const std::string& where) {
    if (w.size() < 2) fail(where, std::string(w[0]) + " without its station names");
    std::vector<std::string_view> out;
    std::string_view rest = w[1];
    while (true) {
      const std::size_t sep = rest.find(settings_.separator);
      out.push_back(rest.substr(0, sep));
      if (sep == std::string_view::npos) break;
      rest = rest.substr(sep + 1);
    }
    if (out.size() != count || std::any_of(out.begin(), out.end(), [](std::string_view n) { return n.empty(); })) {
      fail(where, std::string(w[0]) + " '" + std::string(w[1]) + "': expected " + std::to_string(count) + " station name(s) joined by '" +
                      std::string(1, settings_.separator) + "' (.SEPARATOR changes it)");
    }
    return out;
  }

  void need_format(const std::string& code, const std::string& where) {
    if (settings_.format_dims == 0) {
      fail(where, code + " before any .2D or .3D: whether a STAR*NET line is 2D or 3D data is a project option the data file "
                         "does not hold");
    }
    (settings_.format_dims == 3 ? uses3d_ : uses2d_) = true;
  }
  bool three_d_delta(const std::string& code, const std::string& where) {
    if (settings_.format_dims != 3) return false;
    if (!settings_.delta) {
      fail(where, code + " in 3D data before any .DELTA ON|OFF: whether its distance is slope or horizontal is a project "
                         "option the data file does not hold");
    }
    return true;
  }
  void need_angle_order(const std::string& code, const std::string& where) {
    if (!settings_.at_from_to) {
      fail(where, code + " before any .ORDER AtFromTo|FromAtTo: the station order of angles is a project option the data file "
                         "does not hold");
    }
  }

  void record(const Words& w, const std::string& where) {
    std::string code(w[0]);
    for (char& c : code) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (gps_ && code != "G2" && code != "G3") {
      fail(where, code + " after the G1 of " + gps_->where + " without its " + (gps_->g2.empty() ? "G2 and G3" : "G3") +
                      ": a vector is G1, G2, G3 in that order");
    }
    if (code == "C") return coordinates(w, where);
    if (code == "E" || code == "EH") return elevation(code, w, where);
    if (code == "P" || code == "PH") return position(code, w, where);
    if (code == "A" || code == "M") return angle_line(code, w, where);
    if (code == "D" || code == "V" || code == "DV") return distance_line(code, w, where);
    if (code == "B" || code == "BM") return bearing_line(code, w, where);
    if (code == "L") return levelling(w, where);
    if (code == "DB" || code == "DN" || code == "DM" || code == "DE") return direction_line(code, w, where);
    if (code.size() == 2 && code[0] == 'G' && code[1] >= '0' && code[1] <= '3') return gps_line(code, w, where);
    if (code == "CH") {
      fail(where, "CH (grid coordinates with an ellipsoid height): STAR*NET's grid is the project's map projection, which the "
                  "data file does not name; give geodetic positions (P, PH) or C coordinates of a local network");
    }
    if (code.size() == 2 && code[0] == 'G' && std::isdigit(static_cast<unsigned char>(code[1]))) {
      fail(where, code + ": not a GPS vector line geoanchor reads (G0 name, G1 vector, G2 and G3 its covariance)");
    }
    if (code == "T" || code == "TB" || code == "TE" || code == "SS") {
      fail(where, code + " (traverse or sideshot data): not read by geoanchor; give M, A, D and B lines");
    }
    fail(where, "record '" + std::string(w[0]) + "' is not a STAR*NET data code geoanchor reads (C, E, EH, P, PH, A, D, V, B, "
                "M, BM, DV, L, DB, DN, DM, DE, G0-G3)");
  }

  // C Station North East [Elev] [Std Errors], in the .ORDER given.
  void coordinates(const Words& w, const std::string& where) {
    need_format("C", where);
    if (!geodetic_where_.empty()) {
      fail(where, "C (grid coordinates) with the geodetic positions or GPS vectors of " + geodetic_where_ + ": STAR*NET's grid "
                  "is the project's map projection, which the data file does not name; give P or PH lines");
    }
    if (settings_.format_dims == 3 && settings_.ellipsoid_heights) {
      fail(where, "C in 3D data under .ELEVATION Ellipsoidal (grid coordinates with an ellipsoid height, as CH): the project's "
                  "map projection is not in the data file; give P or PH lines");
    }
    if (plane_where_.empty()) plane_where_ = where;
    if (!settings_.north_first) {
      fail(where, "C before any .ORDER NE|EN: the order of coordinates is a project option the data file does not hold");
    }
    const std::string id(names(w, 1, where)[0]);
    station(id, where);
    const std::size_t n = static_cast<std::size_t>(settings_.format_dims);
    if (w.size() != 2 + n && w.size() != 2 + 2 * n) {
      fail(where, "C " + id + ": " + std::to_string(w.size() - 2) + " values; expected " + std::to_string(n) + " coordinates" +
                      (n == 3 ? " (north, east, elevation)" : " (north, east)") + ", each optionally with a standard error, "
                      "'!' (fixed) or '*' (free)");
    }
    StationText& st = text_of(id, where, "C");
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t axis = k == 2 ? 2 : (k == 0) == *settings_.north_first ? 0 : 1;
      st.value[axis] = starnet::length_m(w[2 + k], settings_, where, k == 2 ? "elevation" : axis == 0 ? "north" : "east");
      if (w.size() > 2 + n) fixity(w[2 + n + k], st, axis, where);
    }
  }

  // E Station Elevation [Std Error]; EH: an ellipsoid height (as E under
  // .ELEVATION Ellipsoidal), on the ellipsoid of an ellipsoidal network.
  void elevation(const std::string& code, const Words& w, const std::string& where) {
    const bool ellipsoidal = code == "EH" || settings_.ellipsoid_heights;
    if (ellipsoidal) geodetic(code + (code == "E" ? " under .ELEVATION Ellipsoidal" : ""), where);
    const std::string id(names(w, 1, where)[0]);
    station(id, where);
    if (w.size() != 3 && w.size() != 4) fail(where, code + " " + id + ": expected an elevation and optionally its standard error, '!' or '*'");
    StationText& st = text_of(id, where, code);
    if (st.value[2]) fail(where, code + " " + id + ": its elevation is given already (" + st.where + ")");
    st.value[2] = starnet::length_m(w[2], settings_, where, ellipsoidal ? "ellipsoid height" : "elevation");
    st.ellipsoid_height = ellipsoidal;
    st.elevation_where = where;
    if (w.size() == 4) fixity(w[3], st, 2, where);
  }

  // The file's stations are on the ellipsoid of an input read before it.
  void geodetic(const std::string& what, const std::string& where) {
    if (!plane_where_.empty()) {
      fail(where, what + " with the C (grid) coordinates of " + plane_where_ + ", which make a local network: give geodetic "
                         "positions (P, PH) or C coordinates, not both");
    }
    if (!geodetic_where_.empty()) return;
    if (net_.space != geodesy::NetworkSpace::ellipsoidal || !net_.frame || !net_.ellipsoid_stated) {
      fail(where, what + ": a STAR*NET data file names no datum; geoanchor reads geodetic positions, ellipsoid heights and GPS "
                         "vectors onto the frame and ellipsoid of an input named before it (network JSON with \"frame\", or "
                         "DynaML), and " + (net_.space == geodesy::NetworkSpace::local ? "the inputs before it make a local network"
                                                                                        : "no input before it names a frame"));
    }
    geodetic_where_ = where;
  }

  // P Station Latitude Longitude [Elevation] [Std Errors]; PH: the
  // elevation is an ellipsoid height (3D data only).
  void position(const std::string& code, const Words& w, const std::string& where) {
    need_format(code, where);
    geodetic(code, where);
    const std::string id(names(w, 1, where)[0]);
    station(id, where);
    const std::size_t n = static_cast<std::size_t>(settings_.format_dims);
    if (code == "PH" && n != 3) fail(where, "PH " + id + " in 2D data: its ellipsoid height is 3D data (.3D)");
    if (w.size() != 2 + n && w.size() != 2 + 2 * n) {
      fail(where, code + " " + id + ": " + std::to_string(w.size() - 2) + " values; expected " +
                      (n == 3 ? "latitude, longitude, elevation" : "latitude, longitude") +
                      ", each optionally with a standard error (m), '!' (fixed) or '*' (free)");
    }
    StationText& st = text_of(id, where, code);
    st.value[0] = starnet::latitude_rad(w[2], settings_, where, net_.warnings);
    st.value[1] = starnet::longitude_rad(w[3], settings_, where, net_.warnings);
    if (n == 3) {
      if (st.value[2]) fail(where, code + " " + id + ": its elevation is given already (" + st.elevation_where + ")");
      st.value[2] = starnet::length_m(w[4], settings_, where, code == "PH" ? "ellipsoid height" : "elevation");
      st.ellipsoid_height = code == "PH" || settings_.ellipsoid_heights;
      st.elevation_where = where;
    }
    for (std::size_t k = 0; w.size() > 2 + n && k < n; ++k) fixity(w[2 + n + k], st, k, where);
  }

  // G0 'name; G1 From-To ΔX ΔY ΔZ; G2 and G3 its covariance.
  void gps_line(const std::string& code, const Words& w, const std::string& where) {
    geodetic(code, where);
    if (code == "G0") {
      // Its text: the descriptor (after "'") or the words after G0.
      const std::size_t quote = line_.find('\'');
      g0_name_.clear();
      if (quote != std::string_view::npos) {
        std::string_view t = line_.substr(quote + 1);
        while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.remove_suffix(1);
        g0_name_ = std::string(t);
      } else {
        for (std::size_t k = 1; k < w.size(); ++k) g0_name_ += (k > 1 ? " " : "") + std::string(w[k]);
      }
      return;
    }
    if (code == "G1") {
      const auto n = names(w, 2, where);
      PendingVector v;
      v.from = station(n[0], where);
      v.to = station(n[1], where);
      v.delta = starnet::gps_delta(w, settings_, where);
      v.where = where;
      v.name = std::exchange(g0_name_, std::string());
      gps_ = std::move(v);
      return;
    }
    if (!gps_) fail(where, code + " without its G1 line before it");
    if (code == "G2") {
      if (!gps_->g2.empty()) fail(where, "G2 given twice for the G1 of " + gps_->where);
      for (const auto t : w) gps_->g2.emplace_back(t);
      gps_->g2_where = where;
      return;
    }
    if (gps_->g2.empty()) fail(where, "G3 before the G2 of the G1 of " + gps_->where);
    const Words g2(gps_->g2.begin(), gps_->g2.end());
    geodesy::NetworkMeasurement m;
    m.kind = MeasurementKind::gnss_baselines;
    m.stations = {gps_->from, gps_->to};
    m.value = gps_->delta;
    m.covariance = starnet::gps_covariance(g2, gps_->g2_where, w, where, settings_);
    m.source = gps_->where;
    if (!gps_->name.empty()) m.metadata.emplace_back("STAR*NET G0", gps_->name);
    net_.measurements.push_back(std::move(m));
    gps_.reset();
  }

  // .REFRACTION k: the network's one coefficient (zenith angles read
  // before it used the project's, which the data file does not hold).
  void refraction(const std::string& where) {
    const double k = *settings_.refraction;
    if (!zenith_where_.empty()) {
      fail(where, ".REFRACTION " + format_shortest(k) + " after the zenith angle of " + zenith_where_ + ", read with STAR*NET's "
                  "project coefficient (not in the data file): put .REFRACTION before the zenith angles");
    }
    if (net_.refraction_k && *net_.refraction_k != k) {
      fail(where, ".REFRACTION " + format_shortest(k) + " differs from the " + format_shortest(*net_.refraction_k) + " of " +
                      net_.refraction_source + ": geoanchor applies one coefficient of refraction to the whole adjustment");
    }
    if (!net_.refraction_k) net_.refraction_k = k, net_.refraction_source = where;
  }

  StationText& text_of(const std::string& id, const std::string& where, const std::string& code) {
    auto [it, fresh] = stations_.try_emplace(id);
    if (fresh) {
      order_.push_back(id);
      it->second.where = where;
    } else if ((code == "C" || code == "P" || code == "PH") && (it->second.value[0] || it->second.value[1])) {
      fail(where, code + " " + id + " is given again (first at " + it->second.where + "); give one C or P line per station");
    } else if (code == "P" || code == "PH") {
      it->second.where = where;
    }
    return it->second;
  }

  // A coordinate's standard error: '!' fixed, '*' free, a number > 0 held
  // with that standard error (5.6, "C" code).
  void fixity(std::string_view w, StationText& st, std::size_t axis, const std::string& where) {
    if (w == "!") {
      st.constraint.code[axis] = 'C';
    } else if (w == "*") {
      st.constraint.code[axis] = 'F';
    } else if (w == "&") {
      fail(where, "'&' (the project's default standard error for coordinates): the data file does not hold it; give '!', '*' "
                  "or a standard error");
    } else {
      const double s = starnet::length_m(w, settings_, where, "coordinate standard error");
      if (!(s > 0.0)) fail(where, "coordinate standard error '" + std::string(w) + "': expected a number > 0, '!' or '*'");
      st.constraint.code[axis] = 'C';
      st.constraint.sigma_m[axis] = s;
    }
  }

  void define(const std::string& id, const StationText& st, int dims) {
    const bool horizontal = st.value[0] && st.value[1];
    if (dims == 2 && !st.elevation_where.empty()) fail(st.elevation_where, "E " + id + ": an elevation in a 2D network");
    if (dims == 3 && horizontal && !st.value[2]) {
      fail(st.where, "C " + id + " has no elevation (2D data and no E line) in a 3D network");
    }
    geodesy::StationConstraint con = st.constraint;
    if (dims == 2) con.code[2] = 'F', con.sigma_m[2] = 0.0;
    if (dims == 1) con.code[0] = con.code[1] = 'F', con.sigma_m[0] = con.sigma_m[1] = 0.0;
    const Eigen::Vector3d p(st.value[0].value_or(0.0), st.value[1].value_or(0.0), st.value[2].value_or(0.0));
    const std::size_t s = builder_.define(id, p, con, st.where);
    net_.stations[s].position_known = dims == 1 ? st.value[2].has_value() : horizontal;
  }

  // An ellipsoidal network: the P/PH (and E/EH) stations on the
  // network's ellipsoid; orthometric elevations need the geoid.
  void finish_geodetic() {
    if (!bearing_where_.empty()) {
      fail(bearing_where_, "a bearing (B, BM) with the geodetic positions or GPS vectors of " + geodetic_where_ + ": whether a "
                           "STAR*NET bearing is a grid bearing or a geodetic azimuth is a project option; geoanchor reads "
                           "bearings in a local network (C coordinates) only");
    }
    const geodesy::GeocentricConverter geo(net_.ellipsoid);
    for (const auto& id : order_) {
      const StationText& st = stations_.at(id);
      if (!st.value[0]) {
        fail(st.where, id + ": an elevation for a station without a P or PH line; geoanchor holds a station of an ellipsoidal "
                            "network by its position");
      }
      if (!st.value[2]) fail(st.where, "P " + id + " has no elevation (2D data and no E or EH line): an ellipsoidal network is 3-D");
      double h = *st.value[2];
      if (!st.ellipsoid_height) {
        const auto n = undulation(id, *st.value[0], *st.value[1], st.elevation_where);
        if (!n) {
          fail(st.elevation_where, id + ": elevation " + format_shortest(h) + " m is orthometric (E, P; .ELEVATION Orthometric) and "
                                   "there is no geoid to make it an ellipsoid height: give --geoid, or EH/PH lines");
        }
        h += *n;
      }
      const Eigen::Vector3d p = geo.ecef_from_geodetic({geodesy::Angle::radians(*st.value[0]), geodesy::Angle::radians(*st.value[1]),
                                                        geodesy::EllipsoidalHeight{h}}).m;
      builder_.define(id, p, st.constraint, st.where);
    }
    for (std::size_t i = before_stations_; i < net_.stations.size(); ++i) {
      geodesy::NetworkStation& s = net_.stations[i];
      if (s.defined) continue;
      builder_.define(s.id, Eigen::Vector3d::Zero(), {}, s.source);
      net_.stations[i].position_known = false;
    }
  }

  // N at station `id`: the per-station geoid file's, else the grid's.
  std::optional<double> undulation(const std::string& id, double lat, double lon, const std::string& where) const {
    if (options_.station_geoid) {
      if (const auto it = options_.station_geoid->by_station.find(id); it != options_.station_geoid->by_station.end()) {
        return it->second.n_m;
      }
    }
    if (!options_.geoid) return std::nullopt;
    return options_.geoid->undulation_m(geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), where);
  }

  // The observations' standard errors (one each, required), and the HI/HT.
  void weigh(std::vector<Obs>& obs, Words rest, bool hiht_allowed, const std::string& where) {
    double hi = 0.0, ht = 0.0;
    if (!rest.empty() && rest.back().find('/') != std::string_view::npos) {
      const std::string_view t = rest.back();
      if (!hiht_allowed) fail(where, "HI/HT '" + std::string(t) + "' on a line without a 3D distance or vertical observation");
      const std::size_t slash = t.find('/');
      hi = starnet::length_m(t.substr(0, slash), settings_, where, "HI");
      ht = starnet::length_m(t.substr(slash + 1), settings_, where, "HT");
      rest.pop_back();
    }
    if (rest.size() != obs.size()) {
      fail(where, std::to_string(rest.size()) + " standard error(s) for " + std::to_string(obs.size()) +
                      " observation(s): geoanchor needs each observation's standard error on its line (STAR*NET's defaults are "
                      "project options the data file does not hold)");
    }
    for (std::size_t k = 0; k < obs.size(); ++k) {
      const std::string_view t = rest[k];
      if (t == "!" || t == "&") {
        fail(where, "standard error '" + std::string(t) + "' (" + (t == "!" ? "a fixed observation" : "the project's default") +
                        "): geoanchor adjusts an observation with its standard error; give a number, or '*' (free)");
      }
      // '*': a free observation, no weight (manual 5.5): read, not adjusted;
      // its covariance is a placeholder of one unit² (m², rad²).
      const bool free = t == "*";
      const bool linear = obs[k].kind == MeasurementKind::slope_distance || obs[k].kind == MeasurementKind::horizontal_distance ||
                          obs[k].kind == MeasurementKind::height_difference;
      const double sigma = free ? 1.0
                           : linear ? starnet::length_m(t, settings_, where, "standard error")
                                    : starnet::angle_sigma_rad(t, settings_, where);
      if (!(sigma > 0.0)) fail(where, "standard error '" + std::string(t) + "': expected a number > 0");
      if (obs[k].kind == MeasurementKind::zenith_angle && !settings_.refraction && zenith_where_.empty()) zenith_where_ = where;
      geodesy::NetworkMeasurement m;
      if (free) {
        m.ignore = true;
        m.metadata.emplace_back("STAR*NET", "free observation ('*'): read, not adjusted");
      }
      m.kind = obs[k].kind;
      m.stations = obs[k].stations;
      m.value = Eigen::VectorXd::Constant(1, obs[k].value);
      m.covariance = Eigen::MatrixXd::Constant(1, 1, sigma * sigma);
      m.source = where;
      m.set = m.kind == MeasurementKind::direction ? set_ : std::nullopt;
      if (m.kind == MeasurementKind::slope_distance || m.kind == MeasurementKind::zenith_angle) {
        m.instrument_height_m = hi, m.target_height_m = ht;
      } else if (m.kind == MeasurementKind::height_difference && obs[k].vertical) {
        m.value(0) += hi - ht;  // instrument-to-target difference to mark-to-mark
      }
      net_.measurements.push_back(std::move(m));
    }
  }

  // The distance and vertical of a 3D line (slope and zenith, or
  // horizontal and elevation difference per .DELTA) or a 2D distance;
  // either may be absent (a V line has no distance, a 2D line no vertical).
  void distance_vertical(std::vector<Obs>& obs, std::optional<std::string_view> distance, std::optional<std::string_view> vertical,
                         std::size_t from, std::size_t to, const std::string& code, const std::string& where) {
    const bool three = three_d_delta(code, where);
    const bool slope = three && !*settings_.delta;
    if (distance) {
      const double d = starnet::length_m(*distance, settings_, where, slope ? "slope distance" : "horizontal distance");
      if (!(d > 0.0)) fail(where, "distance '" + std::string(*distance) + "' must be > 0");
      obs.push_back({slope ? MeasurementKind::slope_distance : MeasurementKind::horizontal_distance, {from, to}, d});
    }
    if (!vertical) return;
    if (!three) fail(where, code + ": a vertical observation is 3D data (.3D)");
    if (slope) {
      obs.push_back({MeasurementKind::zenith_angle, {from, to},
                     starnet::angle_rad(*vertical, MeasurementKind::zenith_angle, settings_, where, net_.warnings), true});
    } else {
      obs.push_back({MeasurementKind::height_difference, {from, to},
                     starnet::length_m(*vertical, settings_, where, "elevation difference"), true});
    }
  }
  // The distance (and in 3D data the vertical) of an M, BM or DM line from w[at].
  void measure(std::vector<Obs>& obs, const Words& w, std::size_t at, std::size_t from, std::size_t to, const std::string& code,
               const std::string& where) {
    const bool three = settings_.format_dims == 3;
    if (w.size() < at + (three ? 2 : 1)) fail(where, code + ": expected its distance" + (three ? " and vertical observation" : ""));
    distance_vertical(obs, w[at], three ? std::optional<std::string_view>(w[at + 1]) : std::nullopt, from, to, code, where);
  }

  static Words tail(const Words& w, std::size_t from) { return Words(w.begin() + static_cast<std::ptrdiff_t>(std::min(from, w.size())), w.end()); }

  // A At-From-To Angle; M At-From-To Angle Distance [Vertical] (5.6).
  void angle_line(const std::string& code, const Words& w, const std::string& where) {
    need_format(code, where);
    need_angle_order(code, where);
    const auto n = names(w, 3, where);
    const std::size_t a = station(n[*settings_.at_from_to ? 0 : 1], where), f = station(n[*settings_.at_from_to ? 1 : 0], where),
                      t = station(n[2], where);
    if (w.size() < 3) fail(where, code + ": expected its angle");
    std::vector<Obs> obs{{MeasurementKind::horizontal_angle, {a, f, t},
                          starnet::angle_rad(w[2], MeasurementKind::horizontal_angle, settings_, where, net_.warnings)}};
    std::size_t next = 3;
    if (code == "M") {
      measure(obs, w, 3, a, t, code, where);
      next = settings_.format_dims == 3 ? 5 : 4;
    }
    weigh(obs, tail(w, next), code == "M" && settings_.format_dims == 3, where);
  }

  // D From-To Distance; V From-To Vertical; DV From-To Distance Vertical (5.6).
  void distance_line(const std::string& code, const Words& w, const std::string& where) {
    need_format(code, where);
    const auto n = names(w, 2, where);
    const std::size_t f = station(n[0], where), t = station(n[1], where);
    if (w.size() < 3) fail(where, code + ": expected its value");
    std::vector<Obs> obs;
    std::size_t next = 3;
    if (code == "D") {
      distance_vertical(obs, w[2], std::nullopt, f, t, code, where);
    } else if (code == "V") {
      distance_vertical(obs, std::nullopt, w[2], f, t, code, where);
    } else {
      if (w.size() < 4) fail(where, "DV: expected a distance and a vertical observation");
      distance_vertical(obs, w[2], w[3], f, t, code, where);
      next = 4;
    }
    weigh(obs, tail(w, next), settings_.format_dims == 3, where);
  }

  // B From-To Bearing; BM From-To Bearing Distance [Vertical] (5.6).
  void bearing_line(const std::string& code, const Words& w, const std::string& where) {
    need_format(code, where);
    const auto n = names(w, 2, where);
    const std::size_t f = station(n[0], where), t = station(n[1], where);
    if (w.size() < 3) fail(where, code + ": expected its bearing or azimuth");
    if (bearing_where_.empty()) bearing_where_ = where;
    std::vector<Obs> obs{{MeasurementKind::azimuth, {f, t}, starnet::azimuth_rad(w[2], settings_, where, net_.warnings)}};
    std::size_t next = 3;
    if (code == "BM") {
      measure(obs, w, 3, f, t, code, where);
      next = settings_.format_dims == 3 ? 5 : 4;
    }
    weigh(obs, tail(w, next), code == "BM" && settings_.format_dims == 3, where);
  }

  // L From-To ElevDiff Distance StdErr: the distance weights STAR*NET's
  // default standard error only, which geoanchor does not apply (the
  // standard error is required); it is read and checked.
  void levelling(const Words& w, const std::string& where) {
    const auto n = names(w, 2, where);
    const std::size_t f = station(n[0], where), t = station(n[1], where);
    if (w.size() < 4) fail(where, "L: expected an elevation difference, a length and a standard error");
    const double dh = starnet::length_m(w[2], settings_, where, "elevation difference");
    const double length = starnet::length_m(w[3], settings_, where, "levelled length");
    if (!(length > 0.0)) fail(where, "L: levelled length '" + std::string(w[3]) + "' must be > 0");
    std::vector<Obs> obs{{MeasurementKind::height_difference, {f, t}, dh}};
    weigh(obs, tail(w, 4), false, where);
  }

  // DB At; DN To Direction; DM To Direction Distance [Vertical]; DE (5.6,
  // direction sets): one orientation unknown per set.
  void direction_line(const std::string& code, const Words& w, const std::string& where) {
    need_format(code, where);
    if (code == "DB") {
      if (set_) fail(where, "DB while the set of " + set_where_ + " is open (no DE)");
      if (w.size() != 2) fail(where, "DB: expected the instrument station alone");
      set_station_ = station(names(w, 1, where)[0], where);
      set_ = net_.direction_sets.size();
      set_where_ = where;
      net_.direction_sets.push_back({set_station_, where});
      return;
    }
    if (!set_) fail(where, code + " outside a direction set (DB … DE)");
    if (code == "DE") {
      if (w.size() != 1) fail(where, "DE: expected nothing after it");
      set_.reset();
      return;
    }
    const std::size_t t = station(names(w, 1, where)[0], where);
    if (w.size() < 3) fail(where, code + ": expected its direction");
    std::vector<Obs> obs{{MeasurementKind::direction, {set_station_, t},
                          starnet::angle_rad(w[2], MeasurementKind::direction, settings_, where, net_.warnings)}};
    std::size_t next = 3;
    if (code == "DM") {
      measure(obs, w, 3, set_station_, t, code, where);
      next = settings_.format_dims == 3 ? 5 : 4;
    }
    weigh(obs, tail(w, next), code == "DM" && settings_.format_dims == 3, where);
  }

  geodesy::Network& net_;
  const NetworkReadOptions& options_;
  NetworkBuilder builder_;
  Settings settings_;
  std::map<std::string, StationText> stations_;
  std::vector<std::string> order_;
  bool uses2d_ = false, uses3d_ = false;
  std::optional<std::size_t> set_;
  std::size_t set_station_ = 0;
  std::string set_where_, first_where_;
  std::string plane_where_, geodetic_where_, bearing_where_, zenith_where_;  // the first C, P/PH/EH/G, B/BM, zenith angle
  std::optional<PendingVector> gps_;
  std::string_view line_;  // the data line being read
  std::string g0_name_;
  std::size_t before_stations_ = 0, before_measurements_ = 0;
};

}  // namespace

void read_starnet(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  Reader reader(into, options);
  reader.start();
  std::vector<std::filesystem::path> stack;
  std::error_code ec;
  if (source != "standard input") stack.push_back(std::filesystem::weakly_canonical(std::filesystem::path(source), ec));
  reader.read(text, std::string(source), 0, stack);
  reader.finish();
}

}  // namespace geoanchor::io::detail
