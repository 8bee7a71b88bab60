#pragma once
// Control points: marks whose coordinates are known in two frames, the
// observations a datum transform is fitted to. Coordinates are ECEF in each
// frame; covariances are ECEF 3×3 in square metres.

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

// How one frame's coordinates were written in the control file, so that a
// diagnosis can read them again another way (swapped, in other units, on
// another projection).
// `crs`: in a CRS read through PROJ (fit --src-crs, "# source_crs = …"),
// whose name is in ControlInputForm::crs_name.
enum class CoordinateForm { ecef, geodetic, enu, projected, crs };

// What a geodetic or projected frame's height column held: ellipsoidal
// heights h (h_src_m, h_m) or orthometric heights H (H_src_m, H_m), which
// the reader turned into h = H + N on a geoid model.
enum class HeightKind { ellipsoidal, orthometric };

struct ControlInputForm {
  CoordinateForm form = CoordinateForm::ecef;
  std::optional<ProjectionDef> projection;  // projected: the declared grid
  HeightKind height_type = HeightKind::ellipsoidal;  // ECEF and ENU: ellipsoidal by construction
  std::string height_column;  // orthometric: the column or key read ("H_dst_m", "H_m")
  std::string geoid_model;    // orthometric: the model N came from ("EGM96", "EGM96-NGA")
  std::string crs_name;       // crs: "EPSG:2236 (NAD83 / Florida East (ftUS))"
  // crs: how PROJ read the role, as a JSON object (the CRS as typed, its
  // WKT2, and PROJ's operation to ECEF with its grids and their SHA-256),
  // for the outputs to record; "" otherwise.
  std::string crs_record_json;
  std::vector<std::string> crs_warnings;  // crs: what PROJ's reading warned of (areas of use, ensembles)
  // The ellipsoid of geodetic, projected and ENU values: the one the frame
  // implies (GRS80 for ITRF, ETRF, GDA, NAD83; WGS84 for WGS 84), or
  // --ellipsoid, or WGS84 for a frame the set does not name.
  Ellipsoid ellipsoid = Ellipsoid::wgs84();
};

// A mark's ECEF velocities (m/yr) in each frame at its epoch, with their
// covariances (m²/yr²): they observe the transform's rates.
struct MarkVelocities {
  Eigen::Vector3d source_m_per_year = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_m_per_year = Eigen::Vector3d::Zero();
  Eigen::Matrix3d source_cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d target_cov = Eigen::Matrix3d::Zero();
};

struct ControlPoint {
  std::string id;
  std::size_t line = 0;  // where it was read, for messages
  EcefPosition source;
  EcefPosition target;
  Eigen::Matrix3d source_cov_m2 = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d target_cov_m2 = Eigen::Matrix3d::Zero();
  // Epoch at which the point's two coordinates are related by the transform.
  std::optional<DecimalYear> epoch;
  bool use = true;
  // The GNSS solution type of the mark's surveyed coordinates (a `solution`
  // column or key; docs/commands/fit.md#gnss-solution-types); nullopt when
  // the set has none. Fits exclude float and worse by default
  // (solver::FitOptions::solutions).
  std::optional<GnssSolution> solution;
  // Optional: the mark's velocities in both frames. Held out of line and
  // shared between copies (never changed once read): most sets have none,
  // and in place they were 40 % of a mark (200 MB of 10⁶ marks).
  std::shared_ptr<const MarkVelocities> velocities;
  // The three numbers of each frame as written (x, y, z | lat, lon, h in
  // degrees and metres | e, n, u | easting, northing, h). For orthometric
  // input the third is the ellipsoidal height read from it (h = H + N), so
  // that reading the first two another way keeps the mark's height.
  Eigen::Vector3d source_as_read = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_as_read = Eigen::Vector3d::Zero();
};

struct ControlSet {
  std::string source_name;  // file name, for messages
  std::vector<ControlPoint> points;
  std::optional<Frame> source_frame;
  std::optional<Frame> target_frame;
  // False when the file gave no sigmas: weights are then equal (1 m²) and
  // only σ0 estimated from the residuals gives them a scale.
  bool has_a_priori_sigmas = true;
  // Every point carries its GNSS solution type (the set has a `solution`
  // column or every JSON point a `solution` key); false when none does.
  bool has_solutions = false;
  // How the coordinates were read: their forms and ellipsoids, the nominal
  // origin of ENU values (on the ellipsoid of the frame whose values are ENU).
  ControlInputForm source_input;
  ControlInputForm target_input;
  std::optional<LocalOrigin> origin;
};

}  // namespace geoanchor::geodesy
