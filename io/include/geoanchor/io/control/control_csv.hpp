#pragma once
// Control sets in CSV. Columns (header-named as in `convert`, with the role
// before the unit):
//
//   id                                       required, unique per epoch
//   source: x_src_m,y_src_m,z_src_m | lat_src_deg,lon_src_deg,h_src_m | e_src_m,n_src_m,u_src_m
//           | easting_src_m,northing_src_m,h_src_m (on the grid given as src_projection);
//           H_src_m in place of h_src_m: orthometric heights, read as h = H + N on src_geoid
//           (refused, naming the column, without one)
//   target: the same with _dst
//   sigma_src_m, sigma_dst_m                 isotropic standard deviations (m), optional
//   cov_src_xx_m2, cov_src_xy_m2, cov_src_xz_m2, cov_src_yy_m2, cov_src_yz_m2, cov_src_zz_m2
//                                            full covariance (m²), likewise dst; axes are those
//                                            of the coordinates (ECEF x,y,z; for geodetic and
//                                            ENU input the local east, north, up)
//   epoch                                    decimal year, optional (required by helmert14)
//   use                                      1/0, true/false, yes/no; optional (default 1)
//
// Frames may be declared in comment lines before the header:
//   # source_frame = ITRF2014@2024.5
//   # target_frame = ETRF2000@2024.5
// A dynamic frame (geodesy::is_dynamic: ITRF, IGS, WGS 84 realizations) must
// name its coordinate epoch there unless every point has an `epoch`;
// otherwise the set is refused naming the comment and the frame.
//
// ENU coordinates need the nominal origin (`origin`). Refusals (geoanchor::
// Error, input): sigma <= 0, NaN/inf, empty or unparsable fields, a
// covariance that is not positive definite, duplicate ids at the same epoch
// (naming both lines and the coordinate difference), sigma and covariance
// columns both given for one frame.

#include <filesystem>
#include <istream>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/crs/crs.hpp"

namespace geoanchor::io {

// A frame the caller gives: `replace` stands for the file's (fit
// --source-frame), `fallback` where the file names none (diagnose
// --transform's frames).
struct CallerFrame {
  std::optional<geodesy::Frame> replace, fallback;
};

struct ControlReadOptions {
  // --ellipsoid: the ellipsoid of both frames' geodetic, projected and ENU
  // values. Without it each frame's is the one the frame implies
  // (geodesy::implied_ellipsoid: GRS80 for ITRF, ETRF, GDA, NAD83; WGS84
  // for WGS 84), else the other frame's, else WGS84 when neither is named
  // or implies one; the set records each (ControlInputForm::ellipsoid).
  // Given, it must not contradict the frame of a role whose values use it
  // (E_ELLIPSOID, usage, naming both).
  std::optional<geodesy::Ellipsoid> ellipsoid;
  CallerFrame source_frame, target_frame;
  // The CRS of each frame's coordinates, read through PROJ (fit and
  // diagnose --src-crs/--dst-crs; a CSV may state them above its header as
  // "# source_crs = EPSG:2236" / "# target_crs = …", and a flag that
  // contradicts the file is refused). The columns are then the CRS's with
  // the role before the unit (easting_src_ftus, lat_dst_deg, h_src_m,
  // H_dst_m with a compound CRS), PROJ converts them to the datum's
  // geocentric coordinates, and the frame is the CRS's catalog frame. A
  // frame with a CRS takes sigma_<role>_m (isotropic, metres) but no
  // covariance columns.
  std::optional<Crs> src_crs, dst_crs;
  // For e_src_m/e_dst_m columns; its ellipsoid is replaced by that of the
  // frame whose values are ENU.
  std::optional<geodesy::LocalOrigin> origin;
  // The grids of easting_src_m/northing_src_m and easting_dst_m/northing_dst_m
  // columns (a UTM zone or a Transverse Mercator, put on the frame's
  // ellipsoid); h_src_m beside them is ellipsoidal. Projected columns
  // without one are refused.
  std::optional<geodesy::ProjectionDef> src_projection;
  std::optional<geodesy::ProjectionDef> dst_projection;
  // The geoid of orthometric heights (H_src_m, H_dst_m; JSON H_m) in each
  // frame: h = H + N. Without one such a column is refused (E_HEIGHT_TYPE,
  // naming it). `fit --geoid` and `diagnose --geoid` set both. Not owned;
  // must outlive the read.
  const geodesy::GeoidGrid* src_geoid = nullptr;
  const geodesy::GeoidGrid* dst_geoid = nullptr;
};

geodesy::ControlSet read_control_csv(std::istream& in, const std::string& source_name, const ControlReadOptions& o);
geodesy::ControlSet read_control_csv(const std::filesystem::path& path, const ControlReadOptions& o);

// The same in JSON:
//   {"source_frame": "ITRF2014@2024.5", "target_frame": "ETRF2000@2024.5",
//    "points": [{"id": "P01",
//                "source": {"lat_deg": …, "lon_deg": …, "h_m": …},   (or x_m/y_m/z_m, or e_m/n_m/u_m;
//                                                                      H_m for orthometric heights)
//                "target": {"x_m": …, "y_m": …, "z_m": …},
//                "sigma_src_m": 0.003, "sigma_dst_m": 0.004,          (or "cov_src_m2": [[…],[…],[…]])
//                "epoch": 2024.5, "use": true}, …]}
// Messages name the JSON path (points[3].source.lat_deg). The frames follow
// the CSV rules (an epoch for a dynamic frame, unless every point has one);
// one frame's heights are all h_m or all H_m.
geodesy::ControlSet read_control_json(std::istream& in, const std::string& source_name, const ControlReadOptions& o);

// A control set from two CSV files, one frame each (fit --src/--dst): the
// marks whose ids are in both, in the source file's order. A source mark
// the target lacks is refused (E_UNMATCHED_ID, listing them) unless
// `unmatched_source_allowed`; the target may hold more marks. `notes` (when
// given) receives, per file, the ids the other lacks. A joined mark whose
// two covariances together are singular is refused naming both lines;
// other messages name the source file's line. Each file's columns
// name no role: id; x_m,y_m,z_m | lat_deg,lon_deg,h_m | e_m,n_m,u_m |
// easting_m,northing_m,h_m (H_m with a geoid) or its CRS's columns; sigma_m,
// or cov_xx_m2 … cov_zz_m2, or sigma_e_m,sigma_n_m,sigma_u_m with
// corr_en,corr_eu,corr_nu (the local east, north, up of geodetic or ENU
// coordinates); use. Comments above the header state "# frame = NAME@EPOCH",
// "# ellipsoid = NAME" (checked against the frame's; adopted where the
// frame implies none) and "# crs = CRS" with "# coordinate_epoch = YEAR".
// The stations CSV of `geoanchor adjust` is such a file: its x_m,y_m,z_m
// are checked against its lat_deg,lon_deg,h_m, its ellipses are derived
// from the sigmas read, and a component its constraint column holds (C)
// may have a zero sigma. A per-point epoch, velocities, a role in a column
// name, a local network's stations, or no id in common are refused by name.
geodesy::ControlSet read_control_pair(const std::filesystem::path& source, const std::filesystem::path& target,
                                      const ControlReadOptions& o, bool unmatched_source_allowed = false,
                                      std::vector<std::string>* notes = nullptr);

// CSV or JSON, by content (a file whose first non-blank character is '{' is JSON).
geodesy::ControlSet read_control_set(const std::filesystem::path& path, const ControlReadOptions& o);

}  // namespace geoanchor::io
