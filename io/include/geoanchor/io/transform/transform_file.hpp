#pragma once
// The transform file: the JSON that `geoanchor fit` writes and `convert` /
// `apply` read. Schema: docs/transform-file.md.
//
//   {"model": "helmert7" | "helmert6" | "translation3" | "helmert14",
//    "convention": "position_vector" | "coordinate_frame",
//    "rotation_model": "small_angle" | "exact",
//    "source_frame": "ITRF2014@2010.0", "target_frame": "GDA2020",
//    "reference_epoch": 2010.0,
//    "parameters": {"tx_m", "ty_m", "tz_m", "rx_arcsec", "ry_arcsec",
//                   "rz_arcsec", "ds_ppm", and for helmert14 the rates
//                   "dtx_m_per_year", ..., "drx_arcsec_per_year", ...,
//                   "dds_ppm_per_year"; for molodensky-badekas the pivot
//                   "px_m", "py_m", "pz_m"}}
//
// Every parameter key carries its unit; mm, mas and ppb spellings are read
// too (tx_mm, rx_mas, ds_ppb, dtx_mm_per_year, drx_mas_per_year,
// dds_ppb_per_year). A parameter given twice in two units, a missing
// convention, a helmert14 without reference_epoch, a missing parameter, any
// unknown key, a key given twice in one object, a key of another model and
// a value of the wrong type are errors naming the file and the key's JSON
// path (FitRecord below says how sigmas and correlations are checked).

#include <array>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <vector>
#include <optional>
#include <span>
#include <string>
#include <variant>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/geodesy/site_calibration.hpp"
#include "geoanchor/io/map_metadata.hpp"

namespace geoanchor::io {

enum class TransformModel { helmert7, helmert6, translation3, helmert14, molodensky_badekas, enu_origin, site_calibration };
std::string_view to_string(TransformModel m);

// What `geoanchor fit` adds to a transform file: the statistics that justify
// the parameters. Read back whole (every key typed, unknown keys refused);
// convert and apply use none of it.
struct FitPointRecord {
  std::string id;
  std::array<double, 3> residual_enu_m{};
  double w_test = 0.0;                 // the w-test of largest magnitude, signed (NaN: untestable, written null)
  std::array<double, 3> w_enu{};       // w-tests along local E, N, U (NaN: untestable, written null)
  std::array<double, 3> redundancy_enu{};
  double mdb_m = 0.0;
  double point_test = 0.0;
  int point_test_dof = 0;
  double point_test_p = 1.0;
  bool outlier = false;
  bool used = true;
  // What became of it in the tests (solver::TestStatus: used, flagged,
  // removed, uncontrolled, ignored; empty: not stated, files before
  // 2026-12), and its place in data snooping's order (0: none; written when > 0).
  std::string status;
  std::size_t snooping_rank = 0;
  std::string note;  // why it was not used
  double robust_weight = 1.0;  // written when < 1 (robust loss)
  std::optional<geodesy::GnssSolution> solution;  // written when the control set states it ("solution": "float")
};

// The GNSS solution types of a fit's marks (a control set with a
// `solution` column): the policy, and per class (every class, best first)
// the marks read, those in the final fit, those left out for their
// solution type, and the factor their sigmas were multiplied by.
// "gnss_solutions": {"policy": "exclude" | "weight",
//                    "classes": {"fixed": {"marks", "used", "excluded", "sigma_factor"}, ...}}
// Checked when read: every class once, used + excluded <= marks, a class
// the policy leaves out used by none and weighted by none, the factors
// those of geodesy::sigma_factor_under.
struct SolutionTally {
  std::uint64_t marks = 0, used = 0, excluded = 0;
  double sigma_factor = 1.0;
};
struct GnssSolutionRecord {
  geodesy::SolutionPolicy policy = geodesy::SolutionPolicy::exclude;
  std::array<SolutionTally, geodesy::kGnssSolutionCount> classes{};  // in the order of geodesy::kGnssSolutions
};

// The control network's horizontal extent in the source frame: the convex
// hull of the used marks in ENU (metres) at their centroid. `apply` measures
// how far a tile lies outside it.
struct ControlExtent {
  // A point this close to the hull is on it (the hull's vertices are the
  // marks, whose own distance comes out at 1e-10 m of rounding).
  static constexpr double kOnHull_m = 1e-3;
  geodesy::LocalOrigin centroid;            // on WGS84, ellipsoidal height
  std::vector<std::array<double, 2>> hull_en_m;  // counter-clockwise

  // The hull of `marks` (ECEF); one or two marks give a point or a segment.
  static ControlExtent of(const std::vector<geodesy::EcefPosition>& marks);
  // Horizontal distance in metres from `x` to the hull; 0 inside.
  double distance_m(const geodesy::EcefPosition& x) const;
  // The largest of distance_m over the points (x[i], y[i], z[i]) (ECEF);
  // NaN when a point is not finite; 0 for none.
  double max_distance_m(std::span<const double> x, std::span<const double> y, std::span<const double> z) const;
};

// The fit record, read back whole from a fitted file (present when the file
// has any of sigmas, correlation, correlation_parameters, statistics, points,
// control_extent). apply and convert use the sigmas, correlation and extent;
// the workbench reopens a saved fit with alpha, alpha_point, the sigmas'
// scaling and each point's id, used, outlier and note.
//
// Sigmas are checked against the model when read: every key names an
// estimated parameter of the file's model as `parameters` spells it (tx_m or
// tx_mm, rz_arcsec or rz_mas, ...; held at canonical units here), finite and
// >= 0. The correlation matrix names exactly the sigma'd parameters
// (correlation_parameters, each once) and is square, symmetric, has a unit
// diagonal, |r| <= 1 and is positive semi-definite; a file with sigmas and
// no matrix is refused unless it says "correlation": "none" (uncorrelated).
struct FitRecord {
  std::vector<std::pair<std::string, double>> sigmas;  // canonical parameter name -> σ (canonical units)
  std::vector<std::string> correlation_names;           // canonical names, the order of `correlation`
  std::vector<std::vector<double>> correlation;
  bool uncorrelated = false;  // "correlation": "none": the sigma'd parameters are uncorrelated
  bool sigmas_scaled_by_sigma0 = false;
  std::optional<double> sigma0;  // undefined without redundancy (written as null)
  int dof = 0;
  double alpha = 0.05;
  double alpha_point = 0.001;
  double global_statistic = 0.0;
  double global_critical_lower = 0.0;
  double global_critical_upper = 0.0;
  bool global_passed = false;
  bool global_applicable = true;
  std::vector<FitPointRecord> points;
  std::vector<std::string> warnings;
  std::optional<std::pair<double, double>> variance_factors;  // source, target (--vce)
  std::string generator;  // "geoanchor 0.1.0 fit ..."
  // "control_crs": how each role of the control set read through a CRS was
  // read ({"source": {...}, "target": {...}}: the CRS, its WKT2, PROJ's
  // operation to ECEF with its grids' SHA-256), as JSON text; "" when none.
  std::string control_crs_json;
  std::optional<ControlExtent> extent;
  std::optional<GnssSolutionRecord> gnss_solutions;  // only for a control set with solution types
};

// enu-origin: a map's ENU frame re-anchored (geodesy::enu_origin_correction).
struct EnuOriginCorrection {
  geodesy::LocalOrigin nominal;
  Eigen::Vector3d shift_enu_m = Eigen::Vector3d::Zero();
  geodesy::Angle yaw;
  geodesy::ScaleDifference ds;
};

struct TransformFile {
  TransformModel model = TransformModel::helmert7;
  geodesy::RotationModel rotation_model = geodesy::RotationModel::small_angle;
  // 7-parameter models hold a Helmert7, helmert14 a Helmert14; the
  // convention is the alternative's type.
  std::variant<geodesy::Helmert7<geodesy::PositionVector>, geodesy::Helmert7<geodesy::CoordinateFrame>,
               geodesy::Helmert14<geodesy::PositionVector>, geodesy::Helmert14<geodesy::CoordinateFrame>>
      helmert;
  std::optional<geodesy::Frame> source_frame;
  std::optional<geodesy::Frame> target_frame;
  std::optional<geodesy::DecimalYear> reference_epoch;  // required for helmert14
  // molodensky-badekas: target = p + T + (1 + ds) R (source − p), with the
  // seven parameters in `helmert` and the pivot p (ECEF metres) here.
  std::optional<Eigen::Vector3d> pivot_m;
  // enu-origin: the correction; `helmert` is unused.
  std::optional<EnuOriginCorrection> enu_origin;
  // site-calibration: the calibration (not an affine map); `helmert` is unused.
  std::optional<geodesy::SiteCalibration> site_calibration;

  // (A member added here must be added to without_fit_record() in
  // transform_file.cpp too: it copies every member by name but fit.)
  std::optional<FitRecord> fit;  // only when written by `geoanchor fit`
  // The map metadata contract (map_metadata.hpp), written by fit and adjust
  // --estimate-helmert: it describes the transform's target side (the
  // frame and epoch the anchored map is in). Read back typed; its frame and
  // epoch must be target_frame's.
  std::optional<MapMetadata> metadata;

  bool time_dependent() const { return model == TransformModel::helmert14; }
  std::string_view convention_name() const;

  // The transform (or its exact inverse) applied to one point, for every
  // model. Throws as target_from_source.
  geodesy::EcefPosition apply(const geodesy::EcefPosition& x, std::optional<geodesy::DecimalYear> observation_epoch,
                              bool inverse, std::string_view where) const;

  // target_from_source in ECEF at `observation_epoch` (not for
  // site-calibration, which is not affine: use apply). Throws
  // geoanchor::Error (input) if the transform is time-dependent and no epoch
  // is given; `where` names what lacks it (a file:line, a flag).
  geodesy::AffineMap target_from_source(std::optional<geodesy::DecimalYear> observation_epoch,
                                        std::string_view where) const;
};

// Throws geoanchor::Error (io for an unreadable file, input for the rest).
TransformFile read_transform_file(const std::filesystem::path& path);
TransformFile parse_transform_json(std::string_view text, std::string_view source_name);

// The file's JSON text (parameters in m, arcsec, ppm and their rates). With
// a fit record it also carries: sigmas, correlation, statistics, points,
// proj_pipeline, epsg_method, and `alternatives` (the same transform in the
// other rotation convention, with its EPSG method). write_json streams the
// same text (the per-point records a megabyte at a time).
std::string to_json_text(const TransformFile& t);
void write_json(std::ostream& out, const TransformFile& t);

// Point records formed as they are written, so that a fit of 10⁶ marks is
// written without first holding 10⁶ records (200 MB): `record(i, out)`
// fills record i of `count`, every field of it (`out` is reused from one
// record to the next). It is called from several threads at once.
struct PointRecordSource {
  std::size_t count = 0;
  std::function<void(std::size_t, FitPointRecord&)> record;
};
// The same text as write_json(out, t) with t.fit->points taken from
// `points` (t.fit must be present and hold no points of its own).
void write_json(std::ostream& out, const TransformFile& t, const PointRecordSource& points);

// The transform as a PROJ pipeline string, ECEF in and ECEF out:
// "+proj=pipeline +step +proj=helmert ... +convention=...". For helmert14
// PROJ takes the observation epoch from each coordinate's time (cct: x y z t).
std::string proj_pipeline(const TransformFile& t);

// The coordinate operation as WKT2:2019 in its EPSG method (1031, 1032/1033,
// 1053/1056, 1034/1061), and as PROJJSON (converted from that WKT by PROJ).
// std::nullopt for the exact rotation model and enu-origin, which no EPSG
// method describes.
std::optional<std::string> to_wkt2(const TransformFile& t);
std::optional<std::string> to_projjson(const TransformFile& t);

// The EPSG method code of the transform in its own convention, e.g.
// "EPSG:1033" (position vector), "EPSG:1032" (coordinate frame), 1053/1056
// for time-dependent sets.
std::string epsg_method(const TransformFile& t);

}  // namespace geoanchor::io
