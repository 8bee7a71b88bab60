#include "geoanchor/io/las_geotiff.hpp"

#include <proj.h>

#include <cmath>
#include <cstring>
#include <map>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {
namespace {

constexpr std::uint16_t kKeyDirectory = 34735;
constexpr std::uint16_t kUserDefined = 32767;

// GeoTIFF 1.0 key ids geoanchor reads.
enum Key : std::uint16_t {
  kModelType = 1024,
  kRasterType = 1025,
  kCitation = 1026,
  kGeographicType = 2048,
  kGeogCitation = 2049,
  kGeogAngularUnits = 2054,
  kProjectedCsType = 3072,
  kPcsCitation = 3073,
  kProjLinearUnits = 3076,
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

}  // namespace

std::optional<LasGeoKeys> las_geotiff_crs(const std::vector<LasVlr>& vlrs, const std::string& where) {
  const LasVlr* dir = nullptr;
  for (const auto& v : vlrs) {
    if (v.user_id == "LASF_Projection" && v.record_id == kKeyDirectory) dir = &v;
  }
  if (!dir) return std::nullopt;
  const auto& d = dir->data;
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
  std::map<std::uint16_t, std::uint16_t> short_values;
  for (std::size_t k = 0; k < keys; ++k) {
    const std::uint16_t id = u16(4 * (k + 1)), location = u16(4 * (k + 1) + 1), value = u16(4 * (k + 1) + 3);
    switch (id) {
      case kCitation:
      case kGeogCitation:
      case kPcsCitation:
      case kVerticalCitation:
        continue;  // text, read by people
      case kModelType:
      case kRasterType:
      case kGeographicType:
      case kGeogAngularUnits:
      case kProjectedCsType:
      case kProjLinearUnits:
      case kVerticalCsType:
      case kVerticalDatum:
      case kVerticalUnits:
        if (location != 0) fail(where, "key " + std::to_string(id) + " is not a short value (TIFF tag " + std::to_string(location) + ")");
        if (short_values.count(id)) fail(where, "key " + std::to_string(id) + " is given twice");
        short_values[id] = value;
        continue;
      default:
        fail(where, "key " + std::to_string(id) +
                        " is not read by geoanchor (a user-defined CRS's parameters, or a key of another kind): give "
                        "the tile's CRS with --crs (EPSG code or WKT), or a WKT record");
    }
  }
  const auto value = [&](std::uint16_t id) -> std::optional<std::uint16_t> {
    const auto it = short_values.find(id);
    return it == short_values.end() ? std::nullopt : std::optional(it->second);
  };
  for (const std::uint16_t id : {kModelType, kGeographicType, kProjectedCsType, kVerticalCsType, kVerticalDatum}) {
    if (value(id) == kUserDefined) {
      fail(where, "key " + std::to_string(id) +
                      " is user-defined (32767): its CRS is stated by parameters geoanchor does not read; give the "
                      "tile's CRS with --crs");
    }
  }
  LasGeoKeys out;
  const auto model = value(kModelType);
  std::string horizontal;
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
    if (const auto units = value(kGeogAngularUnits); units && *units != 9102) {
      fail(where, "GeogAngularUnitsGeoKey " + std::to_string(*units) + ": geoanchor reads degrees (9102)");
    }
  } else if (model) {
    fail(where, "GTModelTypeGeoKey " + std::to_string(*model) + ": geoanchor reads projected (1) and geographic (2) models");
  } else {
    fail(where, "no GTModelTypeGeoKey and no CRS code: the keys state no CRS");
  }
  out.crs = horizontal;
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
  } else if (value(kVerticalUnits) || value(kVerticalDatum)) {
    fail(where, "vertical units or datum without VerticalCSTypeGeoKey (4096): the heights' CRS is not stated; give --crs");
  }
  return out;
}

}  // namespace geoanchor::io
