#include "geoanchor/crs/geotiff_keys.hpp"

#include <geo_normalize.h>
#include <geo_simpletags.h>
#include <geotiff.h>
#include <proj.h>
#include <proj_experimental.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr std::uint16_t kKeyDirectory = 34735;
constexpr std::uint16_t kDoubleParams = 34736;
constexpr std::uint16_t kAsciiParams = 34737;
constexpr std::uint16_t kUserDefined = 32767;

// GeoTIFF 1.0 key ids geoanchor reads.
enum Key : std::uint16_t {
  kModelType = 1024,
  kRasterType = 1025,
  kCitation = 1026,
  kGeographicType = 2048,
  kGeogCitation = 2049,
  kGeogGeodeticDatum = 2050,
  kGeogPrimeMeridian = 2051,
  kGeogLinearUnits = 2052,
  kGeogLinearUnitSize = 2053,
  kGeogAngularUnits = 2054,
  kGeogAngularUnitSize = 2055,
  kGeogEllipsoid = 2056,
  kGeogSemiMajorAxis = 2057,
  kGeogSemiMinorAxis = 2058,
  kGeogInvFlattening = 2059,
  kGeogAzimuthUnits = 2060,
  kGeogPrimeMeridianLong = 2061,
  kGeogToWgs84 = 2062,
  kProjectedCsType = 3072,
  kPcsCitation = 3073,
  kProjection = 3074,
  kProjLinearUnits = 3076,
  kProjLinearUnitSize = 3077,
  kVerticalCsType = 4096,
  kVerticalCitation = 4097,
  kVerticalDatum = 4098,
  kVerticalUnits = 4099,
};

// EPSG linear units a GeoTIFF file names, in metres.
std::optional<double> linear_unit_m(std::uint16_t code) {
  switch (code) {
    case 9001: return 1.0;                // metre
    case 9002: return 0.3048;             // foot
    case 9003: return 1200.0 / 3937.0;    // US survey foot
    case 9036: return 1000.0;             // kilometre
    default: return std::nullopt;
  }
}

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw Error(ErrorKind::input, "E_GEOTIFF_KEYS", where + ": GeoTIFF CRS keys: " + what);
}

// The unit (metres per unit) of the first axis of an EPSG CRS, through PROJ.
double first_axis_unit(const std::string& code, const std::string& where) {
  const detail::PjContext ctx = detail::quiet_context();
  detail::Pj crs(proj_create(ctx.get(), code.c_str()));
  if (!crs) fail(where, code + " is not a CRS PROJ knows");
  detail::Pj horizontal(proj_get_type(crs.get()) == PJ_TYPE_COMPOUND_CRS ? proj_crs_get_sub_crs(ctx.get(), crs.get(), 0)
                                                                          : proj_clone(ctx.get(), crs.get()));
  detail::Pj cs(proj_crs_get_coordinate_system(ctx.get(), horizontal.get()));
  double factor = 0.0;
  if (!cs || !proj_cs_get_axis_info(ctx.get(), cs.get(), 0, nullptr, nullptr, nullptr, &factor, nullptr, nullptr, nullptr)) {
    fail(where, "cannot read the axes of " + code);
  }
  return factor;
}


// The EPSG code PROJ gives an object (a datum, an ellipsoid, a prime
// meridian), or 0 when it has none.
int epsg_code_of(PJ_CONTEXT* ctx, const PJ* object) {
  if (!object) return 0;
  const char* authority = proj_get_id_auth_name(object, 0);
  const char* code = proj_get_id_code(object, 0);
  if (!authority || !code || std::strcmp(authority, "EPSG") != 0) return 0;
  (void)ctx;
  return std::atoi(code);
}

// What the EPSG CRS `code` says its geodetic datum is, for the keys that
// repeat it (GeoTIFF 1.0 section 2.5.3.2 allows them beside a CRS code;
// they must then agree with it).
struct GeodeticFacts {
  int geodetic_crs = 0, datum = 0, ellipsoid = 0, prime_meridian = 0;
  double semi_major_m = 0, semi_minor_m = 0, inverse_flattening = 0, prime_meridian_deg = 0;
};

GeodeticFacts geodetic_facts(const std::string& code, const std::string& where) {
  const detail::PjContext ctx = detail::quiet_context();
  detail::Pj crs(proj_create(ctx.get(), code.c_str()));
  if (!crs) fail(where, code + " is not a CRS PROJ knows");
  detail::Pj geodetic(proj_crs_get_geodetic_crs(ctx.get(), crs.get()));
  if (!geodetic) fail(where, code + " has no geodetic datum");
  GeodeticFacts f;
  f.geodetic_crs = epsg_code_of(ctx.get(), geodetic.get());
  detail::Pj datum(proj_crs_get_datum_forced(ctx.get(), geodetic.get()));
  f.datum = epsg_code_of(ctx.get(), datum.get());
  detail::Pj ellipsoid(proj_get_ellipsoid(ctx.get(), geodetic.get()));
  detail::Pj pm(proj_get_prime_meridian(ctx.get(), geodetic.get()));
  if (!ellipsoid || !pm) fail(where, "cannot read the ellipsoid and prime meridian of " + code);
  f.ellipsoid = epsg_code_of(ctx.get(), ellipsoid.get());
  f.prime_meridian = epsg_code_of(ctx.get(), pm.get());
  int computed = 0;
  proj_ellipsoid_get_parameters(ctx.get(), ellipsoid.get(), &f.semi_major_m, &f.semi_minor_m, &computed, &f.inverse_flattening);
  double pm_longitude = 0, pm_unit_rad = 0;
  proj_prime_meridian_get_parameters(ctx.get(), pm.get(), &pm_longitude, &pm_unit_rad, nullptr);
  f.prime_meridian_deg = pm_longitude * pm_unit_rad * 180.0 / M_PI;
  return f;
}

// Two values a key and PROJ give for one quantity agree to `tolerance`.
void agree(const std::string& where, const std::string& key, double key_value, const std::string& crs, double crs_value,
           double tolerance, const std::string& unit) {
  if (!(std::abs(key_value - crs_value) <= tolerance)) {
    fail(where, key + " " + format_shortest(key_value) + unit + " contradicts " + crs + ", whose value is " +
                    format_shortest(crs_value) + unit);
  }
}


// A user-defined CRS (its projection and datum stated as parameter keys)
// as libgeotiff reads it, GDAL's and PDAL's reader: the PROJ string of
// GTIFGetProj4Defn, or nullopt when libgeotiff cannot make one. The
// records are handed over as in a TIFF file's tags (libgeotiff's simple
// tags).
struct UserDefinedCrs {
  std::string proj;                       // PROJ's string of it
  std::vector<std::uint16_t> parameters;  // the keys its projection takes its parameters from
  std::vector<double> values;             // their values, in degrees and metres
  int method = 0;                         // the GeoTIFF coordinate transformation (CT_*); 0: geographic
};

// The coordinate transformations whose PROJ string libgeotiff 1.7 writes
// with every parameter (each then checked at full precision): it prints
// Oblique Stereographic as stere, drops Stereographic's scale and the
// Hotine Oblique Mercator's rectified grid angle, so those and the rest are
// refused rather than read wrong.
constexpr int kExactMethods[] = {1, 7, 8, 9, 10, 11, 12, 15, 17};  // TM, Mercator, LCC 2SP/1SP, LAEA, Albers, AEQD, polar stereographic, equirectangular

// Whether every value is in the PROJ string as printed (libgeotiff prints
// scale factors with 6 decimals: 0.999947368 became 0.999947, 9 cm at
// 260 km).
bool values_in_proj_string(const std::string& proj, const std::vector<double>& values) {
  std::vector<double> printed;
  for (std::size_t at = proj.find('='); at != std::string::npos; at = proj.find('=', at + 1)) {
    char* end = nullptr;
    const double x = std::strtod(proj.c_str() + at + 1, &end);
    if (end != proj.c_str() + at + 1) printed.push_back(x);
  }
  for (const double v : values) {
    const bool found = std::any_of(printed.begin(), printed.end(),
                                   [&](double x) { return std::abs(x - v) <= 1e-10 * std::max(1.0, std::abs(v)); });
    if (!found) return false;
  }
  return true;
}

std::optional<UserDefinedCrs> libgeotiff_proj_string(const Bytes& directory, const Bytes* doubles, const Bytes* ascii) {
  std::vector<std::uint16_t> shorts(directory.size() / 2);
  std::memcpy(shorts.data(), directory.data(), 2 * shorts.size());
  std::vector<double> numbers(doubles ? doubles->size() / 8 : 0);
  if (!numbers.empty()) std::memcpy(numbers.data(), doubles->data(), 8 * numbers.size());
  std::string text = ascii ? std::string(ascii->begin(), ascii->end()) : std::string();
  ST_TIFF* tags = ST_Create();
  ST_SetKey(tags, kKeyDirectory, static_cast<int>(shorts.size()), STT_SHORT, shorts.data());
  if (!numbers.empty()) ST_SetKey(tags, kDoubleParams, static_cast<int>(numbers.size()), STT_DOUBLE, numbers.data());
  if (!text.empty()) ST_SetKey(tags, kAsciiParams, static_cast<int>(text.size()), STT_ASCII, text.data());
  std::optional<UserDefinedCrs> out;
  GTIF* gtif = GTIFNewSimpleTags(tags);
  GTIFDefn* defn = GTIFAllocDefn();
  if (gtif && defn && GTIFGetDefn(gtif, defn) && defn->DefnSet) {
    char* proj4 = GTIFGetProj4Defn(defn);
    if (proj4 && *proj4) {
      out = UserDefinedCrs{std::string(proj4), {}, {}, defn->Model == 1 ? defn->CTProjection : 0};  // 1: ModelTypeProjected
      for (int k = 0; k < defn->nParms && k < MAX_GTIF_PROJPARMS; ++k) {
        if (defn->ProjParmId[k] > 0) {
          out->parameters.push_back(static_cast<std::uint16_t>(defn->ProjParmId[k]));
          out->values.push_back(defn->ProjParm[k]);
        }
      }
    }
    if (proj4) GTIFFreeMemory(proj4);
  }
  if (defn) GTIFFreeDefn(defn);
  if (gtif) GTIFFree(gtif);
  ST_Destroy(tags);
  if (out) {
    // "+proj=lcc ... +units=m +no_defs": trimmed, as a CRS.
    while (!out->proj.empty() && out->proj.back() == ' ') out->proj.pop_back();
    out->proj += " +type=crs";
  }
  return out;
}

// geotiff_crs's reading of one GeoKeyDirectory: the records, the keys as
// read, the horizontal CRS as it is found, and the steps, which read() takes
// in order.
struct GeoKeyReader {
  GeoKeyReader(const GeoKeyRecords& records_in, const std::string& where_in, bool set_aside, GeoTiffCrs& out_in)
      : records(records_in), where(where_in), set_aside_unread(set_aside), out(out_in) {}

  const GeoKeyRecords& records;
  const std::string& where;
  bool set_aside_unread;
  GeoTiffCrs& out;
  const Bytes* dir = &records.directory;
  const Bytes* doubles = records.doubles;  // GeoDoubleParamsTag: the values of double-valued keys
  const Bytes* ascii = records.ascii;      // GeoAsciiParamsTag: citations
  std::vector<std::uint16_t> unread_keys;  // refused below unless a user-defined CRS reads them
  std::optional<std::string> to_wgs84;     // GeogTOWGS84GeoKey, described
  std::map<std::uint16_t, std::uint16_t> short_values;
  std::map<std::uint16_t, double> double_values;
  std::string horizontal;
  std::optional<std::uint16_t> model;
  bool projected_model = false;

  void read();
  // A key geoanchor does not read: refused, or (set_aside_unread) listed.
  void unread(const std::string& what);
  void read_directory();
  std::optional<std::uint16_t> value(std::uint16_t id) const;
  // A user-defined CRS's keys; false when they are set aside (nothing more is read).
  bool read_user_defined();
  void projection_on_base_code();
  bool parameters_given(const UserDefinedCrs& user);
  void put_on_base(const UserDefinedCrs& user);
  void check_user_units() const;
  // Keys beside CRS codes; false when no CRS the keys state is left.
  bool set_aside_code_keys();
  void horizontal_from_codes();
  void check_repeated_keys();
  void read_vertical();
};

void GeoKeyReader::read() {
  read_directory();
  // A user-defined projected or geographic CRS (code 32767, its projection
  // and datum as parameter keys): read through libgeotiff into PROJ's
  // string of it, put on the geographic CRS the keys name by code; its
  // units, datum keys and Z unit are then checked as for a code.
  model = value(kModelType);
  projected_model = model == 1 || (!model && value(kProjectedCsType));
  const bool user_defined = projected_model ? value(kProjectedCsType) == kUserDefined
                                            : (model == 2 || (!model && value(kGeographicType))) &&
                                                  value(kGeographicType) == kUserDefined;
  if (user_defined) {
    if (!read_user_defined()) return;
  } else if (!set_aside_code_keys()) {
    return;
  }
  if (!user_defined) horizontal_from_codes();
  out.crs = horizontal;
  check_repeated_keys();
  read_vertical();
  if (to_wgs84) out.description += ", GeogTOWGS84GeoKey " + *to_wgs84 + " (a datum-shift hint, not used: PROJ's operations are)";
}

void GeoKeyReader::unread(const std::string& what) {
  if (!set_aside_unread) throw Error(ErrorKind::input, "E_GEOTIFF_KEYS_UNREAD", where + ": GeoTIFF CRS keys: " + what);
  out.set_aside.push_back(what);
}

void GeoKeyReader::read_directory() {
  const auto& d = *dir;
  const auto u16 = [&](std::size_t i) {
    std::uint16_t x = 0;
    std::memcpy(&x, d.data() + 2 * i, 2);
    return x;
  };
  if (d.size() < 8 || d.size() % 2 != 0) fail(where, "the GeoKeyDirectory record holds " + std::to_string(d.size()) + " bytes");
  if (u16(0) != 1) fail(where, "GeoKeyDirectory version " + std::to_string(u16(0)) + "; expected 1");
  const std::size_t keys = u16(3);
  if (d.size() < 8 * (keys + 1)) {
    fail(where, "the GeoKeyDirectory lists " + std::to_string(keys) + " keys in " + std::to_string(d.size()) + " bytes");
  }
  for (std::size_t k = 0; k < keys; ++k) {
    const std::uint16_t id = u16(4 * (k + 1)), location = u16(4 * (k + 1) + 1), value = u16(4 * (k + 1) + 3);
    switch (id) {
      case kCitation:
      case kGeogCitation:
      case kPcsCitation:
      case kVerticalCitation:
        continue;  // text, read by people
      case kGeogLinearUnitSize:
      case kGeogAngularUnitSize:
      case kGeogSemiMajorAxis:
      case kGeogSemiMinorAxis:
      case kGeogInvFlattening:
      case kGeogPrimeMeridianLong:
      case kProjLinearUnitSize: {
        const std::uint16_t count = u16(4 * (k + 1) + 2);
        if (location != kDoubleParams || count != 1) {
          fail(where, "key " + std::to_string(id) + " is not one value of the GeoDoubleParams record (34736)");
        }
        if (!doubles || doubles->size() < 8 * (std::size_t{value} + 1)) {
          fail(where, "key " + std::to_string(id) + " points at double " + std::to_string(value) +
                          ", past the GeoDoubleParams record (34736)");
        }
        double x = 0;
        std::memcpy(&x, doubles->data() + 8 * std::size_t{value}, 8);
        if (!std::isfinite(x)) fail(where, "key " + std::to_string(id) + " is not a finite number");
        if (double_values.count(id)) fail(where, "key " + std::to_string(id) + " is given twice");
        double_values[id] = x;
        continue;
      }
      case kModelType:
      case kRasterType:
      case kGeographicType:
      case kGeogGeodeticDatum:
      case kGeogPrimeMeridian:
      case kGeogLinearUnits:
      case kGeogAngularUnits:
      case kGeogEllipsoid:
      case kGeogAzimuthUnits:
      case kProjectedCsType:
      case kProjection:
      case kProjLinearUnits:
      case kVerticalCsType:
      case kVerticalDatum:
      case kVerticalUnits:
        if (location != 0) fail(where, "key " + std::to_string(id) + " is not a short value (TIFF tag " + std::to_string(location) + ")");
        if (short_values.count(id)) fail(where, "key " + std::to_string(id) + " is given twice");
        short_values[id] = value;
        continue;
      case kGeogToWgs84: {
        // A datum-shift hint to WGS 84 (3 or 7 values): read, not used
        // (PROJ's operations move the points).
        const std::uint16_t count = u16(4 * (k + 1) + 2);
        if (location != kDoubleParams || (count != 3 && count != 7) || !doubles ||
            doubles->size() < 8 * (std::size_t{value} + count)) {
          fail(where, "GeogTOWGS84GeoKey (2062) is not 3 or 7 values of the GeoDoubleParams record (34736)");
        }
        std::string values;
        for (std::uint16_t j = 0; j < count; ++j) {
          double x = 0;
          std::memcpy(&x, doubles->data() + 8 * (std::size_t{value} + j), 8);
          if (!std::isfinite(x)) fail(where, "GeogTOWGS84GeoKey (2062) holds a value that is not a finite number");
          values += (j ? "," : "") + format_shortest(x);
        }
        to_wgs84 = values;
        continue;
      }
      default:
        unread_keys.push_back(id);
        continue;
    }
  }
}

std::optional<std::uint16_t> GeoKeyReader::value(std::uint16_t id) const {
  const auto it = short_values.find(id);
  return it == short_values.end() ? std::nullopt : std::optional(it->second);
}

bool GeoKeyReader::read_user_defined() {
  const std::string what = std::string("the user-defined ") + (projected_model ? "projected" : "geographic") + " CRS (code 32767)";
  if (value(kVerticalCsType) || value(kVerticalDatum)) {
    unread("a vertical CRS beside a user-defined horizontal one is not read; give the tile's CRS with --crs");
    return false;
  }
  projection_on_base_code();
  // Otherwise the parameters, through libgeotiff.
  const auto user = horizontal.empty() ? libgeotiff_proj_string(*dir, doubles, ascii) : std::nullopt;
  if (horizontal.empty() && !user) {
    unread(what + " could not be read from its parameter keys (libgeotiff); give the tile's CRS with --crs");
    return false;
  }
  if (user && projected_model &&
      std::find(std::begin(kExactMethods), std::end(kExactMethods), user->method) == std::end(kExactMethods)) {
    unread(what + ": its coordinate transformation (ProjCoordTransGeoKey " + std::to_string(user->method) +
           ") is not one geoanchor reads exactly from keys; give the tile's CRS with --crs");
    return false;
  }
  if (user && projected_model && (!value(kProjection) || value(kProjection) == kUserDefined) && !parameters_given(*user)) {
    return false;
  }
  if (user && !values_in_proj_string(user->proj, user->values)) {
    unread(what + ": libgeotiff's PROJ string of it (" + user->proj +
           ") does not carry every parameter at full precision; give the tile's CRS with --crs");
    return false;
  }
  if (user) {
    horizontal = user->proj;
    out.description = what.substr(4) + " read from its keys by libgeotiff: " + user->proj;
  }
  if (user) put_on_base(*user);
  check_user_units();
  return true;
}

// A projection named by its EPSG code (ProjectionGeoKey, e.g. 16032 UTM
// zone 32N) on a geographic CRS named by its code, as GDAL writes a CRS
// EPSG has no code for: built by PROJ from the two codes.
void GeoKeyReader::projection_on_base_code() {
  const auto projection = value(kProjection), base_code = value(kGeographicType);
  if (projected_model && projection && *projection != kUserDefined && base_code && *base_code != kUserDefined) {
    const auto units = value(kProjLinearUnits).value_or(9001);
    const auto unit_m = linear_unit_m(units);
    if (!unit_m) fail(where, "ProjLinearUnitsGeoKey " + std::to_string(units) + " is not a linear unit geoanchor reads (9001, 9002, 9003, 9036)");
    const char* unit_name = units == 9001 ? "metre" : units == 9002 ? "foot" : units == 9003 ? "US survey foot" : "kilometre";
    const detail::PjContext ctx = detail::quiet_context();
    detail::Pj conversion(proj_create_from_database(ctx.get(), "EPSG", std::to_string(*projection).c_str(),
                                                    PJ_CATEGORY_COORDINATE_OPERATION, false, nullptr));
    detail::Pj geographic(proj_create(ctx.get(), ("EPSG:" + std::to_string(*base_code)).c_str()));
    if (!conversion || proj_get_type(conversion.get()) != PJ_TYPE_CONVERSION) {
      fail(where, "ProjectionGeoKey " + std::to_string(*projection) + " is not a projection PROJ knows");
    }
    if (!geographic) fail(where, "GeographicTypeGeoKey " + std::to_string(*base_code) + " is not a CRS PROJ knows");
    detail::Pj cs(proj_create_cartesian_2D_cs(ctx.get(), PJ_CART2D_EASTING_NORTHING, unit_name, *unit_m));
    const std::string name = "EPSG:" + std::to_string(*projection) + " on EPSG:" + std::to_string(*base_code);
    detail::Pj crs(cs ? proj_create_projected_crs(ctx.get(), name.c_str(), geographic.get(), conversion.get(), cs.get()) : nullptr);
    const char* wkt = crs ? proj_as_wkt(ctx.get(), crs.get(), PJ_WKT2_2019, nullptr) : nullptr;
    if (!wkt) fail(where, "PROJ cannot put projection EPSG:" + std::to_string(*projection) + " on EPSG:" + std::to_string(*base_code));
    horizontal = wkt;
    out.description = "user-defined projected CRS (code 32767): projection " + name + ", in units " + std::to_string(units);
  }
}

// A projection named by its own code (ProjectionGeoKey, e.g. 16032 UTM
// zone 32N) takes its parameters from EPSG; one given by parameters
// must give each (libgeotiff takes a missing one as 0). GeoTIFF 1.0
// section 6.3.3.3: a false easting may be FalseEasting,
// FalseOriginEasting or CenterEasting, and so on.
bool GeoKeyReader::parameters_given(const UserDefinedCrs& user) {
  static const std::vector<std::vector<std::uint16_t>> kAliases = {
      {3080, 3084, 3088}, {3081, 3085, 3089}, {3082, 3086, 3090}, {3083, 3087, 3091}, {3092, 3093}};
  const auto given = [&](std::uint16_t id) {
    return std::find(unread_keys.begin(), unread_keys.end(), id) != unread_keys.end() || short_values.count(id) ||
           double_values.count(id);
  };
  for (const std::uint16_t id : user.parameters) {
    bool present = given(id);
    for (const auto& group : kAliases) {
      if (std::find(group.begin(), group.end(), id) == group.end()) continue;
      for (const std::uint16_t other : group) present = present || given(other);
    }
    if (!present) {
      unread("the user-defined projection takes its parameter from key " + std::to_string(id) +
             ", which the keys do not give; give the tile's CRS with --crs");
      return false;
    }
  }
  return true;
}

// A projection on a geographic CRS the keys name by code: that CRS (its
// datum, which a PROJ string cannot carry) under the projection.
void GeoKeyReader::put_on_base(const UserDefinedCrs& user) {
  if (const auto base = value(kGeographicType); projected_model && base && *base != kUserDefined) {
    const detail::PjContext ctx = detail::quiet_context();
    detail::Pj crs(proj_create(ctx.get(), user.proj.c_str()));
    detail::Pj geographic(proj_create(ctx.get(), ("EPSG:" + std::to_string(*base)).c_str()));
    if (!crs || !geographic) fail(where, "GeographicTypeGeoKey " + std::to_string(*base) + " is not a CRS PROJ knows");
    detail::Pj altered(proj_crs_alter_geodetic_crs(ctx.get(), crs.get(), geographic.get()));
    const char* wkt = altered ? proj_as_wkt(ctx.get(), altered.get(), PJ_WKT2_2019, nullptr) : nullptr;
    if (!wkt) fail(where, "the user-defined projection cannot be put on GeographicTypeGeoKey " + std::to_string(*base));
    horizontal = wkt;
    out.description += " on EPSG:" + std::to_string(*base);
  }
}

void GeoKeyReader::check_user_units() const {
  if (const auto units = value(kProjLinearUnits); units && projected_model) {
    const auto m = linear_unit_m(*units);
    const double crs_m = first_axis_unit(horizontal, where);
    if (!m || std::abs(*m - crs_m) > 1e-12 * crs_m) {
      fail(where, "ProjLinearUnitsGeoKey " + std::to_string(*units) + " contradicts the user-defined CRS, whose axes are in units of " +
                      format_shortest(crs_m) + " m");
    }
  }
}

bool GeoKeyReader::set_aside_code_keys() {
  // A projection code beside a CRS code says what the code says; not read.
  if (value(kProjection)) unread_keys.push_back(kProjection);
  for (const std::uint16_t id : unread_keys) {
    unread("key " + std::to_string(id) +
           " is not read by geoanchor (a user-defined CRS's parameters, or a key of another kind): give "
           "the tile's CRS with --crs (EPSG code or WKT), or a WKT record");
  }
  for (const std::uint16_t id : {kModelType, kGeographicType, kProjectedCsType, kVerticalCsType, kVerticalDatum,
                                 kGeogGeodeticDatum, kGeogPrimeMeridian, kGeogEllipsoid, kGeogLinearUnits,
                                 kGeogAngularUnits, kGeogAzimuthUnits, kProjLinearUnits, kVerticalUnits}) {
    if (value(id) == kUserDefined) {
      unread("key " + std::to_string(id) +
             " is user-defined (32767): its CRS is stated by parameters geoanchor does not read; give the "
             "tile's CRS with --crs");
      short_values.erase(id);  // set aside: as if absent
      if (id == kProjectedCsType || id == kGeographicType || id == kModelType) return false;  // no CRS the keys state
    }
  }
  return true;
}

// The horizontal CRS the codes name.
void GeoKeyReader::horizontal_from_codes() {
  if (model == 1 || (!model && value(kProjectedCsType))) {
    if (!value(kProjectedCsType)) fail(where, "model type 1 (projected) without ProjectedCSTypeGeoKey (3072)");
    horizontal = "EPSG:" + std::to_string(*value(kProjectedCsType));
    out.description = "ProjectedCSTypeGeoKey " + std::to_string(*value(kProjectedCsType));
    if (const auto units = value(kProjLinearUnits)) {
      const auto m = linear_unit_m(*units);
      if (!m) fail(where, "ProjLinearUnitsGeoKey " + std::to_string(*units) + " is not a linear unit geoanchor reads (9001, 9002, 9003, 9036)");
      const double crs_m = first_axis_unit(horizontal, where);
      if (std::abs(*m - crs_m) > 1e-12 * crs_m) {
        fail(where, "ProjLinearUnitsGeoKey " + std::to_string(*units) + " (" + format_shortest(*m) + " m) contradicts " +
                        horizontal + ", whose axes are in units of " + format_shortest(crs_m) + " m");
      }
      out.description += ", ProjLinearUnitsGeoKey " + std::to_string(*units);
    }
  } else if (model == 2 || (!model && value(kGeographicType))) {
    if (!value(kGeographicType)) fail(where, "model type 2 (geographic) without GeographicTypeGeoKey (2048)");
    horizontal = "EPSG:" + std::to_string(*value(kGeographicType));
    out.description = "GeographicTypeGeoKey " + std::to_string(*value(kGeographicType));
  } else if (model) {
    fail(where, "GTModelTypeGeoKey " + std::to_string(*model) + ": geoanchor reads projected (1) and geographic (2) models");
  } else {
    fail(where, "no GTModelTypeGeoKey and no CRS code: the keys state no CRS");
  }
}

// Keys that repeat what the CRS code states (a datum, an ellipsoid, a
// prime meridian and their numbers, units' sizes) are read and must
// agree with it: a tile whose keys name EPSG:4326 but Clarke 1866 is
// refused, not moved as either.
void GeoKeyReader::check_repeated_keys() {
  const double rad_per_deg = M_PI / 180.0;
  if (const auto a = value(kGeogAngularUnits); a && *a != 9102) {
    fail(where, "GeogAngularUnitsGeoKey " + std::to_string(*a) + ": geoanchor reads degrees (9102)");
  }
  if (const auto a = value(kGeogAzimuthUnits); a && *a != 9102) {
    fail(where, "GeogAzimuthUnitsGeoKey " + std::to_string(*a) + ": geoanchor reads degrees (9102)");
  }
  if (const auto size = double_values.find(kGeogAngularUnitSize); size != double_values.end()) {
    agree(where, "GeogAngularUnitSizeGeoKey", size->second, "a degree", rad_per_deg, 1e-12, " rad");
  }
  double ellipsoid_unit_m = 1.0;
  if (const auto units = value(kGeogLinearUnits)) {
    const auto m = linear_unit_m(*units);
    if (!m) fail(where, "GeogLinearUnitsGeoKey " + std::to_string(*units) + " is not a linear unit geoanchor reads (9001, 9002, 9003, 9036)");
    ellipsoid_unit_m = *m;
  }
  if (const auto size = double_values.find(kGeogLinearUnitSize); size != double_values.end()) {
    agree(where, "GeogLinearUnitSizeGeoKey", size->second, "GeogLinearUnitsGeoKey", ellipsoid_unit_m, 1e-12 * ellipsoid_unit_m, " m");
    ellipsoid_unit_m = size->second;
  }
  if (const auto size = double_values.find(kProjLinearUnitSize); size != double_values.end()) {
    if (value(kGeographicType) && !value(kProjectedCsType)) fail(where, "ProjLinearUnitSizeGeoKey (3077) in a geographic model");
    const double crs_m = first_axis_unit(horizontal, where);
    agree(where, "ProjLinearUnitSizeGeoKey", size->second, horizontal, crs_m, 1e-12 * crs_m, " m");
  }
  const bool repeats_datum = value(kGeogGeodeticDatum) || value(kGeogPrimeMeridian) || value(kGeogEllipsoid) ||
                             double_values.count(kGeogSemiMajorAxis) || double_values.count(kGeogSemiMinorAxis) ||
                             double_values.count(kGeogInvFlattening) || double_values.count(kGeogPrimeMeridianLong);
  if (repeats_datum || (projected_model && value(kGeographicType))) {
    const GeodeticFacts f = geodetic_facts(horizontal, where);
    if (const auto v = value(kGeographicType); v && projected_model) {
      agree(where, "GeographicTypeGeoKey", *v, horizontal + "'s geographic CRS EPSG code", f.geodetic_crs, 0, "");
    }
    if (const auto v = value(kGeogGeodeticDatum)) agree(where, "GeogGeodeticDatumGeoKey", *v, horizontal + "'s datum EPSG code", f.datum, 0, "");
    if (const auto v = value(kGeogEllipsoid)) agree(where, "GeogEllipsoidGeoKey", *v, horizontal + "'s ellipsoid EPSG code", f.ellipsoid, 0, "");
    if (const auto v = value(kGeogPrimeMeridian)) {
      agree(where, "GeogPrimeMeridianGeoKey", *v, horizontal + "'s prime meridian EPSG code", f.prime_meridian, 0, "");
    }
    constexpr double kAxisTolerance_m = 1e-4;
    if (const auto v = double_values.find(kGeogSemiMajorAxis); v != double_values.end()) {
      agree(where, "GeogSemiMajorAxisGeoKey", v->second * ellipsoid_unit_m, horizontal, f.semi_major_m, kAxisTolerance_m, " m");
    }
    if (const auto v = double_values.find(kGeogSemiMinorAxis); v != double_values.end()) {
      agree(where, "GeogSemiMinorAxisGeoKey", v->second * ellipsoid_unit_m, horizontal, f.semi_minor_m, kAxisTolerance_m, " m");
    }
    if (const auto v = double_values.find(kGeogInvFlattening); v != double_values.end()) {
      agree(where, "GeogInvFlatteningGeoKey", v->second, horizontal, f.inverse_flattening, 1e-6, "");
    }
    if (const auto v = double_values.find(kGeogPrimeMeridianLong); v != double_values.end()) {
      agree(where, "GeogPrimeMeridianLongGeoKey", v->second, horizontal, f.prime_meridian_deg, 1e-9, " deg");
    }
    out.description += ", with its datum keys";
  }
}

// The vertical CRS, or the unit of Z alone.
void GeoKeyReader::read_vertical() {
  if (const auto v = value(kVerticalCsType)) {
    const std::string vertical = "EPSG:" + std::to_string(*v);
    out.crs = horizontal + "+" + std::to_string(*v);
    out.description += ", VerticalCSTypeGeoKey " + std::to_string(*v);
    if (const auto units = value(kVerticalUnits)) {
      const auto m = linear_unit_m(*units);
      if (!m) fail(where, "VerticalUnitsGeoKey " + std::to_string(*units) + " is not a linear unit geoanchor reads (9001, 9002, 9003)");
      const double crs_m = first_axis_unit(vertical, where);
      if (std::abs(*m - crs_m) > 1e-12 * crs_m) {
        fail(where, "VerticalUnitsGeoKey " + std::to_string(*units) + " (" + format_shortest(*m) + " m) contradicts " + vertical +
                        ", whose heights are in units of " + format_shortest(crs_m) +
                        " m: give the tile's CRS with --crs (the vertical CRS in those units)");
      }
      out.description += ", VerticalUnitsGeoKey " + std::to_string(*units);
    }
  } else if (value(kVerticalDatum)) {
    fail(where, "VerticalDatumGeoKey (4098) without VerticalCSTypeGeoKey (4096): the heights' CRS is not stated; give --crs");
  } else if (const auto units = value(kVerticalUnits)) {
    // The unit of Z alone (as many writers state it): it must be the unit
    // the 2-D CRS's heights are taken in, that of its axes (metres for a
    // geographic CRS).
    const auto m = linear_unit_m(*units);
    if (!m) fail(where, "VerticalUnitsGeoKey " + std::to_string(*units) + " is not a linear unit geoanchor reads (9001, 9002, 9003)");
    const bool projected = model == 1 || (!model && value(kProjectedCsType));
    const double z_m = projected ? first_axis_unit(horizontal, where) : 1.0;
    if (std::abs(*m - z_m) > 1e-12 * z_m) {
      fail(where, "VerticalUnitsGeoKey " + std::to_string(*units) + " says Z is in units of " + format_shortest(*m) +
                      " m without a vertical CRS, and " + horizontal + " takes heights in units of " + format_shortest(z_m) +
                      " m: give the tile's CRS with --crs (a compound CRS with a vertical CRS in that unit)");
    }
    out.description += ", VerticalUnitsGeoKey " + std::to_string(*units);
  }
}

}  // namespace

GeoTiffCrs geotiff_crs(const GeoKeyRecords& records, const std::string& where, bool set_aside_unread) {
  GeoTiffCrs out;
  GeoKeyReader reader(records, where, set_aside_unread, out);
  reader.read();
  return out;
}

}  // namespace geoanchor::io
