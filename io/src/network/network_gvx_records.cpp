// What a GVX file's records mean in the network (network_gvx.hpp):
//  - REFERENCE_SYSTEM: its ID is the geodetic datum's number in the ISO
//    Geodetic Register (the schema's rule: "126" for NAD 83(2011), "724"
//    for IGb14), read through the table below; its units must be metres
//    and decimal degrees (the only ones GVX 1.0 allows);
//  - POINT: a set of coordinates of a mark (its NAME) in a reference system
//    at an epoch: the a-priori position of the station NAME, free;
//  - GNSS_VECTOR: ECEF_DELTAS from INITIAL_POINT to TERMINAL_POINT (metres)
//    with the standard deviations and correlations of CORRELATION_MATRIX,
//    in the reference system of its ORBIT at the middle of its
//    OBSERVATION_TIME: one gnss_baselines measurement; SURVEY_SETUP's
//    SOLUTION_TYPE and the terminal point's POINT_TYPE its solution type;
//  - everything else a vector's records say is kept as its metadata.

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/crs/frame_ellipsoid.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/physical_range.hpp"
#include "network/network_builder.hpp"
#include "network/network_gvx.hpp"

namespace geoanchor::io::detail::gvx {
namespace {

using geodesy::GnssSolution;

// The geodetic datums of the ISO Geodetic Register NGS names, by their
// register number, as NGS's GVX tools map them (ISO_Lookup in
// validation_lookup_and_reformatting.py of github.com/noaa-ngs/ngs_xml,
// 2021): the frame geoanchor spells for each.
struct IsoDatum {
  std::string_view id, frame;
};
constexpr std::array kIsoDatums = {
    IsoDatum{"156", "WGS84(Transit)"}, IsoDatum{"116", "WGS84(G730)"},   IsoDatum{"135", "WGS84(G873)"},
    IsoDatum{"114", "WGS84(G1150)"},   IsoDatum{"196", "WGS84(G1674)"},  IsoDatum{"131", "WGS84(G1762)"},
    IsoDatum{"192", "ITRF89"},         IsoDatum{"143", "ITRF91"},        IsoDatum{"103", "ITRF92"},
    IsoDatum{"122", "ITRF93"},         IsoDatum{"197", "ITRF94"},        IsoDatum{"146", "ITRF96"},
    IsoDatum{"145", "ITRF97"},         IsoDatum{"165", "ITRF2000"},      IsoDatum{"105", "ITRF2005"},
    IsoDatum{"179", "ITRF2008"},       IsoDatum{"175", "ITRF2014"},      IsoDatum{"142", "IGS97"},
    IsoDatum{"194", "IGS00"},          IsoDatum{"115", "IGb00"},         IsoDatum{"202", "IGS05"},
    IsoDatum{"106", "IGS08"},          IsoDatum{"159", "IGb08"},         IsoDatum{"153", "IGS14"},
    IsoDatum{"724", "IGb14"},          IsoDatum{"126", "NAD83(2011)"},   IsoDatum{"188", "NAD83(PA11)"},
    IsoDatum{"101", "NAD83(MA11)"},    IsoDatum{"161", "NAD83(1986)"},   IsoDatum{"119", "NAD83(HARN)"},
    IsoDatum{"176", "NAD83(FBN)"},     IsoDatum{"112", "NAD83(CORS96)"}, IsoDatum{"134", "NAD83(NSRS2007)"},
    IsoDatum{"113", "NAD83(PACP00)"},  IsoDatum{"162", "NAD83(MARP00)"},
};

// A point's geodetic and geocentric coordinates agree to this: GVX writes
// latitude and longitude to ten decimals of a degree (1e-5 m) and heights
// and X, Y, Z to four decimals of a metre.
constexpr double kSameCoordinates_m = 1e-3;
// Two records of one mark whose coordinates differ by more are named in a
// warning (the first defines the station; they only start the iteration).
constexpr double kSameMark_m = 1e-3;

struct Context {
  const std::string& source;
  geodesy::Network& net;
  std::map<std::string, const Record*> by_id;  // every record with an ID
  std::vector<const Record*> reference_systems;
};

[[noreturn]] void fail(const Context& c, std::size_t line, const std::string& what) {
  throw Error(ErrorKind::input, "E_GVX", c.source + ":" + std::to_string(line) + ": " + what);
}

const std::string& required(const Context& c, const Record& r, std::string_view path) {
  const Leaf* l = r.find(path);
  if (!l) {
    fail(c, r.line, r.type + (r.find("ID") ? " " + r.text("ID") : "") + " has no " + std::string(path) +
                        " (or it is empty); GVX 1.0 requires it");
  }
  return l->text;
}

double number(const Context& c, const Record& r, std::string_view path) {
  required(c, r, path);
  return *parse_finite_double(r.text(path));  // the type was checked as the leaf was read
}

// The record of type `type` that `r`'s `path` refers to.
const Record& referenced(const Context& c, const Record& r, std::string_view path, std::string_view type) {
  const std::string& id = required(c, r, path);
  const auto it = c.by_id.find(id);
  if (it == c.by_id.end() || it->second->type != type) {
    fail(c, r.find(path)->line, r.type + " " + r.text("ID") + ": " + std::string(path) + " '" + id + "' names no " +
                                    std::string(type) + " of the file");
  }
  return *it->second;
}

// A REFERENCE_SYSTEM's frame name, checked: its units, its register number
// known and reachable through geoanchor's frame catalog (N5), and its NAME
// not another frame of the table.
std::string frame_name(const Context& c, const Record& rs) {
  const std::string& id = required(c, rs, "ID");
  required(c, rs, "LINEAR_UNIT/NAME");   // metres: the only value the schema allows (checked as read)
  required(c, rs, "ANGULAR_UNIT/NAME");  // decimal degrees, likewise
  const auto it = std::find_if(kIsoDatums.begin(), kIsoDatums.end(), [&](const IsoDatum& d) { return d.id == id; });
  if (it == kIsoDatums.end()) {
    std::string list;
    for (const auto& d : kIsoDatums) list += (list.empty() ? "" : ", ") + std::string(d.id) + " " + std::string(d.frame);
    fail(c, rs.find("ID")->line, "REFERENCE_SYSTEM ID " + id + " (NAME '" + rs.text("NAME") +
                                     "') is not a geodetic datum of the ISO Geodetic Register geoanchor knows; expected one of " +
                                     list + " (a coordinate reference system's number, e.g. 216, is not a datum's)");
  }
  const std::string frame(it->frame);
  const auto known = geodesy::catalog_frame_names();
  if (std::find(known.begin(), known.end(), frame) == known.end()) {
    std::string list;
    for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
    fail(c, rs.find("ID")->line, "REFERENCE_SYSTEM ID " + id + " is " + frame +
                                     ", a frame geoanchor's catalog does not reach (it knows " + list + ")");
  }
  // NAME is for people, yet one naming another frame of the table contradicts the ID.
  if (const std::string& name = rs.text("NAME"); !name.empty()) {
    try {
      const std::string named = geodesy::Frame::parse(name, "NAME").name();
      const bool other = std::any_of(kIsoDatums.begin(), kIsoDatums.end(), [&](const IsoDatum& d) { return d.frame == named; });
      if (other && named != frame) {
        fail(c, rs.find("NAME")->line, "REFERENCE_SYSTEM ID " + id + " is " + frame + " but its NAME '" + name + "' is " + named);
      }
    } catch (const Error& e) {
      if (e.code() == "E_GVX") throw;  // the contradiction; a NAME that is no frame name is only a label
    }
  }
  return frame;
}

struct Point {
  const Record* record = nullptr;
  geodesy::Frame frame;
  Eigen::Vector3d ecef;
};

Point point_of(const Context& c, const Record& p) {
  const Record& rs = referenced(c, p, "COORDINATES/REFERENCE_SYSTEM_ID", "REFERENCE_SYSTEM");
  const double epoch = number(c, p, "COORDINATES/EPOCH");
  const std::string where = c.source + ":" + std::to_string(p.find("COORDINATES/EPOCH")->line) + ": POINT " + p.text("ID") + " EPOCH";
  const geodesy::Frame frame = geodesy::Frame::parse(frame_name(c, rs) + "@" + geodesy::format_decimal_year(geodesy::DecimalYear{epoch}), where);
  const double lat = number(c, p, "COORDINATES/GEODETIC_COORDINATES/LATITUDE");
  const double lon = number(c, p, "COORDINATES/GEODETIC_COORDINATES/LONGITUDE");
  const double h = number(c, p, "COORDINATES/GEODETIC_COORDINATES/ELLIPSOIDAL_HEIGHT");
  const std::string name = "POINT " + p.text("ID") + ": ";
  if (!(std::fabs(lat) <= 90.0)) fail(c, p.find("COORDINATES/GEODETIC_COORDINATES/LATITUDE")->line, name + "LATITUDE " + format_shortest(lat) + " not in [-90, 90] degrees");
  if (!(std::fabs(lon) <= 360.0)) fail(c, p.find("COORDINATES/GEODETIC_COORDINATES/LONGITUDE")->line, name + "LONGITUDE " + format_shortest(lon) + " not in [-360, 360] degrees");
  if (!geodesy::is_physical_height(h)) {
    fail(c, p.find("COORDINATES/GEODETIC_COORDINATES/ELLIPSOIDAL_HEIGHT")->line,
         name + "ELLIPSOIDAL_HEIGHT " + format_shortest(h) + " m is not a height on the Earth: expected " + geodesy::physical_height_range_text());
  }
  // The frame's own ellipsoid, never a default (every frame frame_name
  // accepts is in the catalog, which knows its ellipsoid).
  const auto on = frame_ellipsoid(frame, where);
  if (!on) fail(c, p.line, name + "frame " + frame.name() + ": its ellipsoid is unknown");
  const geodesy::Ellipsoid e = on->ellipsoid;
  const Eigen::Vector3d xyz =
      geodesy::ecef_from_geodetic(e, {geodesy::Angle::degrees(lat), geodesy::Angle::degrees(lon), geodesy::EllipsoidalHeight{h}}).m;
  const int given = (p.find("COORDINATES/GEOCENTRIC_COORDINATES/X") ? 1 : 0) + (p.find("COORDINATES/GEOCENTRIC_COORDINATES/Y") ? 1 : 0) +
                    (p.find("COORDINATES/GEOCENTRIC_COORDINATES/Z") ? 1 : 0);
  if (given != 0) {
    Eigen::Vector3d g;  // in order: the first missing one is named
    g.x() = number(c, p, "COORDINATES/GEOCENTRIC_COORDINATES/X");
    g.y() = number(c, p, "COORDINATES/GEOCENTRIC_COORDINATES/Y");
    g.z() = number(c, p, "COORDINATES/GEOCENTRIC_COORDINATES/Z");
    if ((g - xyz).norm() > kSameCoordinates_m) {
      fail(c, p.line, name + "GEOCENTRIC_COORDINATES are " + format_fixed((g - xyz).norm(), 4) +
                          " m from its GEODETIC_COORDINATES on " + e.name() + "; expected the same point (within 1 mm)");
    }
  }
  return {&p, frame, xyz};
}

// The vector's solution type from how it was derived and how its terminal
// point's coordinates were: RTK fixed, float (partly fixed too), code;
// post-processed fixed as ppk. Points keyed in, adjusted or from PPP say
// nothing of the vector's ambiguities: none.
std::optional<GnssSolution> solution_of(const std::string& solution_type, const std::string& point_type) {
  if (point_type == "Fixed") return solution_type == "Post-processed" ? GnssSolution::ppk : GnssSolution::fixed;
  if (point_type == "Float" || point_type == "PartialFixed") return GnssSolution::floating;
  if (point_type == "Code") return GnssSolution::dgps;
  return std::nullopt;
}

using Metadata = std::vector<std::pair<std::string, std::string>>;

void keep(Metadata& md, const std::string& prefix, const Record& r, std::initializer_list<std::string_view> mapped) {
  for (const auto& l : r.leaves) {
    const bool is_mapped = std::any_of(mapped.begin(), mapped.end(), [&](std::string_view m) {
      return l.path == m || (l.path.size() > m.size() && l.path.compare(0, m.size(), m) == 0 && l.path[m.size()] == '/');
    });
    if (!is_mapped) md.emplace_back(prefix.empty() ? l.path : l.path.empty() ? prefix : prefix + "/" + l.path, l.text);
  }
}

// The covariance (m²) from standard deviations and correlations, refused
// when a deviation is not positive, a correlation outside [−1, 1] or the
// matrix not positive definite (N2).
Eigen::Matrix3d covariance_of(const Context& c, const Record& v) {
  const std::string name = "GNSS_VECTOR " + v.text("ID") + ": CORRELATION_MATRIX ";
  std::array<double, 3> sd{};
  constexpr std::array<std::string_view, 3> kSd = {"CORRELATION_MATRIX/SDX", "CORRELATION_MATRIX/SDY", "CORRELATION_MATRIX/SDZ"};
  for (std::size_t k = 0; k < 3; ++k) {
    sd[k] = number(c, v, kSd[k]);
    if (!(sd[k] > 0.0)) fail(c, v.find(kSd[k])->line, name + std::string(kSd[k].substr(19)) + "=" + v.text(kSd[k]) + " m must be > 0");
  }
  constexpr std::array<std::string_view, 3> kRho = {"CORRELATION_MATRIX/PXY", "CORRELATION_MATRIX/PXZ", "CORRELATION_MATRIX/PYZ"};
  std::array<double, 3> rho{};
  for (std::size_t k = 0; k < 3; ++k) {
    rho[k] = number(c, v, kRho[k]);
    if (!(std::fabs(rho[k]) <= 1.0)) {
      fail(c, v.find(kRho[k])->line, name + std::string(kRho[k].substr(19)) + "=" + v.text(kRho[k]) +
                                         " is a correlation coefficient: expected one in [-1, 1]");
    }
  }
  Eigen::Matrix3d q;
  q << sd[0] * sd[0], rho[0] * sd[0] * sd[1], rho[1] * sd[0] * sd[2],  //
      rho[0] * sd[0] * sd[1], sd[1] * sd[1], rho[2] * sd[1] * sd[2],   //
      rho[1] * sd[0] * sd[2], rho[2] * sd[1] * sd[2], sd[2] * sd[2];
  // A correlation matrix of determinant 1e-12 or less (|ρ| within 5e-7 of
  // 1 alone) gives the vector no weight along some direction.
  constexpr double kSmallestRelative = 1e-12;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(q, Eigen::EigenvaluesOnly);
  const double low = eig.eigenvalues()(0), high = eig.eigenvalues()(2);
  if (!(low > kSmallestRelative * high)) {
    fail(c, v.find("CORRELATION_MATRIX/SDX")->line,
         name + "is not positive definite: smallest eigenvalue " + format_shortest(low) + " m² (largest " + format_shortest(high) +
             " m²); the correlations PXY=" + v.text(kRho[0]) + ", PXZ=" + v.text(kRho[1]) + ", PYZ=" + v.text(kRho[2]) +
             " contradict each other");
  }
  return q;
}

// The frame (with the observation epoch) of a vector.
geodesy::Frame vector_frame(const Context& c, const Record& v) {
  const Record* rs = nullptr;
  if (v.find("QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID")) {
    rs = &referenced(c, v, "QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID", "REFERENCE_SYSTEM");
  } else if (c.reference_systems.size() == 1) {
    rs = c.reference_systems.front();
  } else {
    fail(c, v.line, "GNSS_VECTOR " + v.text("ID") + ": its ORBIT names no REFERENCE_SYSTEM_ID and the file has " +
                        std::to_string(c.reference_systems.size()) +
                        " REFERENCE_SYSTEMs: the frame of its ECEF_DELTAS is not stated");
  }
  const double start = *gps_seconds_of(required(c, v, "OBSERVATION_TIME/START"));
  const double end = *gps_seconds_of(required(c, v, "OBSERVATION_TIME/END"));
  if (!(end >= start)) {
    fail(c, v.find("OBSERVATION_TIME/END")->line, "GNSS_VECTOR " + v.text("ID") + ": OBSERVATION_TIME END " +
                                                      v.text("OBSERVATION_TIME/END") + " is before its START " +
                                                      v.text("OBSERVATION_TIME/START"));
  }
  const geodesy::DecimalYear epoch = geodesy::decimal_year_from_gps_seconds(0.5 * (start + end));
  return geodesy::Frame::parse(frame_name(c, *rs) + "@" + geodesy::format_decimal_year(epoch),
                               c.source + ":" + std::to_string(v.line) + ": GNSS_VECTOR " + v.text("ID") + " OBSERVATION_TIME");
}

// The warnings of one file's points: records no vector uses, several
// records of one mark, and points in another frame or epoch than the
// network's.
struct PointNotes {
  std::size_t other_frame = 0, differing = 0;
  std::string first_other_frame, first_differing;
};

}  // namespace

void read_records(const Document& doc, const std::string& source, geodesy::Network& net) {
  Context c{source, net, {}, {}};
  if (!(net.stations.empty() && net.measurements.empty()) && net.space != geodesy::NetworkSpace::ellipsoidal) {
    fail(c, 1, "GNSS vectors in ECEF, but the other inputs are a local network");
  }
  std::map<std::string, std::size_t> id_line;
  const Record* source_data = nullptr;
  const Record* project = nullptr;
  std::vector<const Record*> remarks, vectors;
  for (const auto& r : doc.records) {
    if (r.type == "SOURCE_DATA") source_data = &r;
    if (r.type == "PROJECT_INFORMATION") project = &r;
    if (r.type == "REMARK") remarks.push_back(&r);
    if (r.type == "REFERENCE_SYSTEM") c.reference_systems.push_back(&r);
    if (r.type == "GNSS_VECTOR") vectors.push_back(&r);
    if (r.type == "REFERENCE_SYSTEM" || r.type == "EQUIPMENT" || r.type == "SURVEY_SETUP" || r.type == "POINT" || r.type == "GNSS_VECTOR") {
      const std::string& id = required(c, r, "ID");
      if (const auto [it, fresh] = c.by_id.emplace(id, &r); !fresh) {
        fail(c, r.find("ID")->line, r.type + " ID " + id + " is the ID of the " + it->second->type + " at line " +
                                        std::to_string(it->second->line) + "; GVX identifiers are unique in the file");
      }
    }
  }
  for (const Record* rs : c.reference_systems) frame_name(c, *rs);
  if (vectors.empty()) fail(c, 1, "no GNSS_VECTOR: nothing to adjust");

  NetworkBuilder builder(net);
  std::map<std::string, Point> defined;  // mark NAME -> the record that defined it here
  std::map<const Record*, std::size_t> used;  // POINT record -> its station
  PointNotes notes;
  const auto station = [&](const Record& p) -> std::size_t {
    if (const auto it = used.find(&p); it != used.end()) return it->second;
    const std::string& name = required(c, p, "NAME");
    const Point pt = point_of(c, p);
    const std::string at = source + ":" + std::to_string(p.line);
    if (!net.frame) {
      net.frame = pt.frame;
      if (const auto e = frame_ellipsoid(pt.frame, at)) net.ellipsoid = e->ellipsoid, net.ellipsoid_stated = true;
    }
    if (!(*net.frame == pt.frame) && notes.other_frame++ == 0) {
      notes.first_other_frame = "POINT " + p.text("ID") + " (" + at + ") in " + pt.frame.to_string();
    }
    std::size_t index = 0;
    if (const auto it = defined.find(name); it != defined.end()) {
      const double d = (it->second.ecef - pt.ecef).norm();
      if (d > kSameMark_m && notes.differing++ == 0) {
        notes.first_differing = "POINT " + p.text("ID") + " (" + at + ") is " + format_fixed(d, 4) + " m from POINT " +
                                it->second.record->text("ID") + " of " + name;
      }
      index = builder.reference(name, at);
    } else {
      defined.emplace(name, pt);
      index = builder.define(name, pt.ecef, geodesy::StationConstraint{}, at);
    }
    used.emplace(&p, index);
    return index;
  };

  std::vector<geodesy::NetworkMeasurement> out;
  out.reserve(vectors.size());
  for (const Record* vp : vectors) {
    const Record& v = *vp;
    const Record& from = referenced(c, v, "INITIAL_POINT_ID", "POINT");
    const Record& to = referenced(c, v, "TERMINAL_POINT_ID", "POINT");
    const Record& setup = referenced(c, v, "SURVEY_SETUP_ID", "SURVEY_SETUP");
    required(c, setup, "SOLUTION_TYPE");
    if (required(c, from, "NAME") == required(c, to, "NAME")) {
      fail(c, v.line, "GNSS_VECTOR " + v.text("ID") + " runs from point " + from.text("NAME") + " to itself");
    }
    geodesy::NetworkMeasurement m;
    m.kind = geodesy::MeasurementKind::gnss_baselines;
    m.source = source + ":" + std::to_string(v.line);
    m.stations = {station(from), station(to)};
    Eigen::Vector3d d;  // in order: the first missing one is named
    d.x() = number(c, v, "ECEF_DELTAS/DX");
    d.y() = number(c, v, "ECEF_DELTAS/DY");
    d.z() = number(c, v, "ECEF_DELTAS/DZ");
    m.value = d;
    m.covariance = covariance_of(c, v);
    m.frame = vector_frame(c, v);
    m.solution = solution_of(setup.text("SOLUTION_TYPE"), to.text("POINT_TYPE"));
    Metadata& md = m.metadata;
    keep(md, "GNSS_VECTOR", v, {"INITIAL_POINT_ID", "TERMINAL_POINT_ID", "SURVEY_SETUP_ID", "ECEF_DELTAS", "CORRELATION_MATRIX"});
    keep(md, "SURVEY_SETUP", setup, {});
    for (const auto& [prefix, p] : {std::pair<std::string, const Record*>{"INITIAL_POINT", &from}, {"TERMINAL_POINT", &to}}) {
      keep(md, prefix, *p, {"NAME", "EQUIPMENT_ID", "COORDINATES/REFERENCE_SYSTEM_ID", "COORDINATES/EPOCH",
                            "COORDINATES/GEODETIC_COORDINATES", "COORDINATES/GEOCENTRIC_COORDINATES"});
      if (p->find("EQUIPMENT_ID")) keep(md, prefix + "/EQUIPMENT", referenced(c, *p, "EQUIPMENT_ID", "EQUIPMENT"), {});
    }
    if (v.find("QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID") || c.reference_systems.size() == 1) {
      const Record& rs = v.find("QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID")
                             ? referenced(c, v, "QUALITY_CONTROL/ORBIT/REFERENCE_SYSTEM_ID", "REFERENCE_SYSTEM")
                             : *c.reference_systems.front();
      keep(md, "REFERENCE_SYSTEM", rs, {"LINEAR_UNIT/NAME", "ANGULAR_UNIT/NAME"});
    }
    if (source_data) keep(md, "SOURCE_DATA", *source_data, {});
    if (project) keep(md, "PROJECT_INFORMATION", *project, {});
    for (const Record* r : remarks) keep(md, "REMARK", *r, {});
    out.push_back(std::move(m));
  }
  std::size_t unused = 0;
  std::string first_unused;
  for (const auto& r : doc.records) {
    if (r.type != "POINT" || used.count(&r)) continue;
    point_of(c, r);  // checked all the same
    if (unused++ == 0) first_unused = "POINT " + r.text("ID") + " (" + r.text("NAME") + ", line " + std::to_string(r.line) + ")";
  }
  if (unused > 0) {
    net.warnings.push_back(source + ": " + std::to_string(unused) + " POINT record(s) no GNSS_VECTOR uses are no stations (" +
                           first_unused + " the first)");
  }
  if (notes.differing > 0) {
    net.warnings.push_back(source + ": " + std::to_string(notes.differing) +
                           " POINT record(s) of a mark already given differ from its first by more than 1 mm (" +
                           notes.first_differing + "); the first record's coordinates start the adjustment");
  }
  if (notes.other_frame > 0) {
    net.warnings.push_back(source + ": " + std::to_string(notes.other_frame) + " POINT record(s) are not in the stations' frame " +
                           net.frame->to_string() + " (" + notes.first_other_frame +
                           " the first); their coordinates only start the adjustment of free stations");
  }
  for (auto& m : out) net.measurements.push_back(std::move(m));
}

}  // namespace geoanchor::io::detail::gvx
