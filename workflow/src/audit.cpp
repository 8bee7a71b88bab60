// `geoanchor audit` as a library: audit_map runs a map's checks (each in
// audit_checks.cpp, audit_seams.cpp, audit_checkpoints.cpp) on its
// artifacts; the measures the checks share (float32 spacing, tangent-plane
// departure, Web Mercator) are public for the tests.
#include "geoanchor/workflow/audit.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numbers>

#include "audit_artifacts.hpp"
#include "audit_checks.hpp"
#include "audit_moves.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::workflow {

using namespace audit_detail;

std::string_view to_string(AuditArtifactKind k) {
  switch (k) {
    case AuditArtifactKind::tile: return "tile";
    case AuditArtifactKind::vector_map: return "vector map";
    case AuditArtifactKind::transform: return "transform file";
  }
  return "?";
}

std::string_view to_string(AuditStatus s) {
  switch (s) {
    case AuditStatus::pass: return "pass";
    case AuditStatus::fail: return "fail";
    case AuditStatus::not_run: return "not run";
  }
  return "?";
}

bool AuditResult::passed() const {
  return std::none_of(checks.begin(), checks.end(), [](const AuditCheck& c) { return c.status == AuditStatus::fail; });
}

double float32_spacing(double x) {
  const float f = static_cast<float>(std::abs(x));
  return static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity()) - f);
}

double tangent_plane_departure_m(double distance_m, double lat_deg, const geodesy::Ellipsoid& e) {
  const double s = std::sin(lat_deg * std::numbers::pi / 180.0);
  const double w2 = 1.0 - e.e2() * s * s;
  const double n = e.a_m() / std::sqrt(w2), m = e.a_m() * (1.0 - e.e2()) / (w2 * std::sqrt(w2));
  const double r = std::sqrt(m * n);  // Gaussian mean radius of curvature
  return distance_m * distance_m / (2.0 * r);
}

std::string web_mercator_mention(std::string_view text) {
  std::string low(text);
  std::transform(low.begin(), low.end(), low.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
  std::string squeezed;  // without blanks and quotes: ID["EPSG",3857] -> id[epsg,3857]
  for (const char ch : low) {
    if (ch != ' ' && ch != '"' && ch != '\'' && ch != '\t' && ch != '\n') squeezed += ch;
  }
  for (const char* name : {"pseudo-mercator", "pseudo mercator", "popular visualisation", "popular visualization", "web mercator",
                           "web_mercator", "google mercator"}) {
    if (low.find(name) != std::string::npos) return "names \"" + std::string(name) + "\"";
  }
  for (const char* code : {"epsg:3857", "epsg,3857]", "epsg::3857", "epsg:900913", "epsg,900913]", "epsg:3785", "epsg,3785]",
                           "esri:102100", "esri,102100]", "esri:102113", "esri,102113]", "epsg:102100"}) {
    const std::string c(code);
    const auto at = squeezed.find(c);
    if (at != std::string::npos) {
      const std::size_t end = at + c.size();
      if (c.back() == ']' || end == squeezed.size() || !std::isdigit(static_cast<unsigned char>(squeezed[end]))) {
        return "identified as " + c;
      }
    }
  }
  if (squeezed.find("+proj=merc") != std::string::npos &&
      (squeezed.find("+a=6378137+b=6378137") != std::string::npos || squeezed.find("+r=6378137") != std::string::npos)) {
    return "a spherical +proj=merc on the WGS 84 semi-major axis";
  }
  return "";
}

AuditResult audit_map(const AuditRequest& request) {
  const AuditLimits& l = request.limits;
  for (const auto& [v, flag] : {std::pair{l.checkpoint_horizontal_m, "--max-checkpoint-horizontal-m"},
                                {l.checkpoint_vertical_m, "--max-checkpoint-vertical-m"}, {l.seam_m, "--max-seam-m"},
                                {l.float32_resolution_m, "--max-float32-spacing-m"}, {l.tangent_plane_m, "--max-tangent-departure-m"},
                                {l.adjacency_gap_m, "--adjacency-gap-m"}}) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw Error(ErrorKind::usage, "E_OPTION", std::string(flag) + " " + format_shortest(v) + ": expected a positive length in metres");
    }
  }
  if (!(l.min_rtk_fixed_percent >= 0.0 && l.min_rtk_fixed_percent <= 100.0)) {
    throw Error(ErrorKind::usage, "E_OPTION", "--min-rtk-fixed-percent " + format_shortest(l.min_rtk_fixed_percent) + ": expected 0 to 100");
  }
  Listing listing = list_artifacts(request);
  AuditResult r;
  r.artifacts = std::move(listing.artifacts);
  r.ignored = std::move(listing.ignored);
  for (auto& a : r.artifacts) read_artifact(a);
  // A map is its tiles and vector maps: a folder of transforms alone is none
  // (it passed with 0 tiles).
  if (std::none_of(r.artifacts.begin(), r.artifacts.end(), [](const AuditArtifact& a) { return a.kind != AuditArtifactKind::transform; })) {
    std::string given;
    for (const auto& m : request.inputs) given += (given.empty() ? "" : ", ") + m;
    throw Error(ErrorKind::input, "E_MAP_EMPTY",
                given + ": no tile or vector map to audit (" + std::to_string(r.artifacts.size()) +
                    " transform files): a map's audit needs its tiles and maps with their sidecars");
  }
  Transforms transforms(r.artifacts);
  r.checks.push_back(check_data(r.artifacts));
  r.checks.push_back(check_metadata(r.artifacts));
  r.checks.push_back(check_one_frame(r.artifacts));
  r.checks.push_back(check_seams(r.artifacts, l, transforms));
  r.checks.push_back(check_checkpoints(r.artifacts, request, transforms));
  r.checks.push_back(check_rtk(r.artifacts, l));
  r.checks.push_back(check_float32_ecef(r.artifacts));
  r.checks.push_back(check_float32_resolution(r.artifacts, l));
  r.checks.push_back(check_tangent_plane(r.artifacts, l));
  r.checks.push_back(check_web_mercator(r.artifacts));
  return r;
}

}  // namespace geoanchor::workflow
