// WKT2:2019 and PROJJSON of a transform file's coordinate operation, in the
// EPSG methods the transform is defined by.

#include <cstdio>
#include <memory>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/crs/crs.hpp"
#include "geoanchor/io/transform/transform_file.hpp"
#include "geoanchor/crs/wkt_text.hpp"

namespace geoanchor::io {
namespace {

using geodesy::CoordinateFrame;
using geodesy::PositionVector;

constexpr double kSecondsPerYear = 31556925.445;  // the "year" of EPSG's rate units
constexpr double kArcsecond_rad = 4.84813681109536e-06;

std::string geocentric_crs(const std::optional<geodesy::Frame>& frame, const char* fallback) {
  const std::string name = frame ? frame->name() : fallback;
  return "GEODCRS[\"" + name + "\",DATUM[\"" + name +
         "\",ELLIPSOID[\"GRS 1980\",6378137,298.257222101,LENGTHUNIT[\"metre\",1]]],"
         "CS[Cartesian,3],AXIS[\"(X)\",geocentricX,ORDER[1],LENGTHUNIT[\"metre\",1]],"
         "AXIS[\"(Y)\",geocentricY,ORDER[2],LENGTHUNIT[\"metre\",1]],"
         "AXIS[\"(Z)\",geocentricZ,ORDER[3],LENGTHUNIT[\"metre\",1]]]";
}

using detail::kWktMetre;
using detail::wkt_parameter;
const std::string& kMetre = kWktMetre;
const std::string kArcsec = "ANGLEUNIT[\"arc-second\",4.84813681109536E-06]";
const std::string kPpm = "SCALEUNIT[\"parts per million\",1E-06]";
std::string per_year(const char* kind, const char* name, double factor) {
  return std::string(kind) + "[\"" + name + "\"," + format_shortest(factor / kSecondsPerYear) + "]";
}

}  // namespace

std::optional<std::string> to_wkt2(const TransformFile& t) {
  if (t.enu_origin || t.site_calibration || t.rotation_model == geodesy::RotationModel::exact) {
    return std::nullopt;  // no EPSG method
  }
  const bool pv = t.convention_name() == PositionVector::name;
  std::string method;
  int code = 0;
  if (t.model == TransformModel::translation3) {
    method = "Geocentric translations (geocentric domain)";
    code = 1031;
  } else if (t.pivot_m) {
    method = pv ? "Molodensky-Badekas (PV geocentric domain)" : "Molodensky-Badekas (CF geocentric domain)";
    code = pv ? 1061 : 1034;
  } else if (t.time_dependent()) {
    method = pv ? "Time-dependent Position Vector tfm (geocentric)" : "Time-dependent Coordinate Frame rotation (geocen)";
    code = pv ? 1053 : 1056;
  } else {
    method = pv ? "Position Vector transformation (geocentric domain)" : "Coordinate Frame rotation (geocentric domain)";
    code = pv ? 1033 : 1032;
  }
  std::string params;
  auto seven = [&](const auto& h) {
    params += wkt_parameter("X-axis translation", h.t_m.x(), kMetre, 8605);
    params += wkt_parameter("Y-axis translation", h.t_m.y(), kMetre, 8606);
    params += wkt_parameter("Z-axis translation", h.t_m.z(), kMetre, 8607);
    if (t.model == TransformModel::translation3) return;
    params += wkt_parameter("X-axis rotation", h.rx.arcsec(), kArcsec, 8608);
    params += wkt_parameter("Y-axis rotation", h.ry.arcsec(), kArcsec, 8609);
    params += wkt_parameter("Z-axis rotation", h.rz.arcsec(), kArcsec, 8610);
    params += wkt_parameter("Scale difference", h.ds.ppm(), kPpm, 8611);
  };
  std::visit([&](const auto& h) {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> || std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
      seven(h.at_reference_epoch);
      const auto& r = h.rates;
      const std::string m = per_year("LENGTHUNIT", "metres per year", 1.0);
      const std::string a = per_year("ANGLEUNIT", "arc-seconds per year", kArcsecond_rad);
      const std::string s = per_year("SCALEUNIT", "parts per million per year", 1e-6);
      params += wkt_parameter("Rate of change of X-axis translation", r.dt_m_per_year.x(), m, 1040);
      params += wkt_parameter("Rate of change of Y-axis translation", r.dt_m_per_year.y(), m, 1041);
      params += wkt_parameter("Rate of change of Z-axis translation", r.dt_m_per_year.z(), m, 1042);
      params += wkt_parameter("Rate of change of X-axis rotation", r.drx_per_year.arcsec(), a, 1043);
      params += wkt_parameter("Rate of change of Y-axis rotation", r.dry_per_year.arcsec(), a, 1044);
      params += wkt_parameter("Rate of change of Z-axis rotation", r.drz_per_year.arcsec(), a, 1045);
      params += wkt_parameter("Rate of change of Scale difference", r.dds_per_year.ppm(), s, 1046);
      params += wkt_parameter("Parameter reference epoch", h.reference_epoch.year, "TIMEUNIT[\"year\",31556925.445]", 1047);
    } else {
      seven(h);
    }
  }, t.helmert);
  if (t.pivot_m) {
    params += wkt_parameter("Ordinate 1 of evaluation point", t.pivot_m->x(), kMetre, 8617);
    params += wkt_parameter("Ordinate 2 of evaluation point", t.pivot_m->y(), kMetre, 8618);
    params += wkt_parameter("Ordinate 3 of evaluation point", t.pivot_m->z(), kMetre, 8667);
  }
  const std::string name = (t.source_frame ? t.source_frame->to_string() : std::string("source")) + " to " +
                           (t.target_frame ? t.target_frame->to_string() : std::string("target")) + " (geoanchor fit)";
  return "COORDINATEOPERATION[\"" + name + "\",SOURCECRS[" + geocentric_crs(t.source_frame, "source") + "],TARGETCRS[" +
         geocentric_crs(t.target_frame, "target") + "],METHOD[\"" + method + "\",ID[\"EPSG\"," + std::to_string(code) +
         "]]" + params + "]";
}

std::optional<std::string> to_projjson(const TransformFile& t) {
  const auto wkt = to_wkt2(t);
  if (!wkt) return std::nullopt;
  return projjson_from_wkt(*wkt);
}

}  // namespace geoanchor::io
