#pragma once
// `geoanchor locate` as a library: the audit trail of labelled map points
// (docs/commands/locate.md). Each point's ENU coordinates at the map's
// origin (the aerodrome reference point its metadata states) become ECEF
// and geodetic coordinates in the map's frame, and, on request, in another
// frame at another epoch through the frame catalog's published paths; with
// the standard deviations the map's transform propagates to the point.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow {

struct LocateRequest {
  std::vector<std::string> map;      // the map's folders or files, as audit reads them
  std::vector<std::string> exclude;  // globs, as audit's
  std::string points;                // CSV: id,e_m,n_m,u_m
  std::optional<std::string> to;     // FRAME[@EPOCH]
  std::optional<std::string> plate;  // the plate the points are on, for an epoch change
  std::string plate_model = "ITRF2020";
  // A point farther than this outside the control network of the map's
  // transform (without one: from the map's ENU origin) is refused, as
  // apply refuses a tile (issue 40 point 3).
  double max_extrapolation_m = 10000.0;
};

struct LocatedPoint {
  std::string id;
  std::size_t line = 0;
  Eigen::Vector3d enu_m = Eigen::Vector3d::Zero();
  geodesy::EcefPosition ecef;
  geodesy::GeodeticPosition geodetic;  // on the map frame's ellipsoid
  // From the map's transform (ENU at the point, m²); nullopt when the map
  // was moved by none or its transform file carries no sigmas.
  std::optional<Eigen::Matrix3d> covariance_enu_m2;
  std::optional<geodesy::EcefPosition> to_ecef;
  std::optional<geodesy::GeodeticPosition> to_geodetic;
};

struct LocateResult {
  MapReference map;
  std::vector<LocatedPoint> points;
  std::optional<geodesy::Frame> to;
  std::optional<geodesy::Ellipsoid> to_ellipsoid;
  std::string path_description;  // the catalog's steps
  double path_accuracy_m = 0.0;  // their stated accuracies combined, and the plate model's over the epoch change
  std::vector<std::string> notes;
};

// Throws geoanchor::Error naming the file, line and column of a bad point
// (a column other than id, e_m, n_m, u_m; a value that is no finite
// number; a duplicate id), the flag of a bad frame or plate, or what the
// map does not state (map_reference).
LocateResult locate_points(const LocateRequest& request);

// A CSV row per point: id, ENU, ECEF, geodetic in the map's frame, its σ
// east/north/up, and the second frame's ECEF and geodetic; the trail (map,
// origin and its source, transform, frame path) in '#' lines above.
std::string locate_csv(const LocateResult& r);
// The same as JSON (schema geoanchor.locate/1), indented by 2.
std::string locate_json_text(const LocateResult& r);

}  // namespace geoanchor::workflow
