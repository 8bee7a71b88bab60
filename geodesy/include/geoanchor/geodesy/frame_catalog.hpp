#pragma once
// Published transformations between terrestrial reference frames, each with
// its source, convention, reference epoch and stated accuracy, and the plate
// motion models that carry coordinates from one epoch to another.
//
// Every parameter set is stored as its source publishes it, turned into
// this library's form: a 14-parameter Helmert in the position-vector
// convention (rotations and rates as the IERS tables give them) with
// `to = T(from)` at the observation epoch t, the parameters evaluated at t
// (p(t) = p + ṗ (t − t_ref)). The reverse of an edge is its exact inverse
// at t. Units on entry: millimetres, milliarc-seconds, parts per billion
// and their rates per year, as the IERS tables print them.
//
// In the catalog (docs/frames.md):
//   - the ITRF family: the IERS sets from ITRF2020, ITRF2014 and ITRF2008 to
//     every earlier realization back to ITRF88;
//   - ETRF89…ETRF2020 (EUREF TN1);
//   - NAD83(2011) from ITRF2008/2014/2020 (NGS), NAD83(CSRSv6/v7/v8) from
//     ITRF2008/2014/2020 (NRCan);
//   - GDA94 → GDA2020 and ITRF2014 → GDA2020 (ICSM);
//   - the WGS 84 realizations G730…G2139 (NGA, as EPSG records them) and
//     G2296 (NGA's announcement: aligned with ITRF2020);
//   - the ITRF2014 and ITRF2020 plate motion models.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/geodesy/helmert.hpp"
#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/units.hpp"

namespace geoanchor::geodesy {

struct CatalogTransformation {
  std::string from, to;               // frame names as Frame::name() prints them: "ITRF2020", "ITRF2014"
  Helmert14<PositionVector> params;   // to = params(from), evaluated at the observation epoch
  double accuracy_m = 0.0;            // as the source (or EPSG, for the same operation) states it
  std::string source;                 // the publication and table
  std::string epsg;                   // the same operation in the EPSG dataset ("EPSG:9991"), or empty
  bool epsg_reversed = false;         // EPSG publishes it in the opposite direction
  // Whether any rate is non-zero (then the observation epoch matters).
  bool time_dependent() const;
};

// A plate's rotation pole in a frame: v = ω × x (ECEF, m/yr for x in m),
// plus the horizontal part of the model's origin rate bias where the model
// has one (ITRF2020-PMM: its authors advise adding the bias to the
// predicted horizontal velocities and discarding the vertical part).
struct PlateMotionModel {
  std::string frame;  // "ITRF2014", "ITRF2020"
  std::string plate;  // "EURA", "NOAM", "AUST", ...
  Eigen::Vector3d omega_mas_per_year = Eigen::Vector3d::Zero();
  Eigen::Vector3d origin_rate_bias_m_per_year = Eigen::Vector3d::Zero();
  std::string source;
  // How well the rigid rotation represents the plate's sites: the published
  // WRMS of the residual horizontal velocities, east and north (mm/yr), and
  // where it is published.
  double wrms_east_mm_per_year = 0.0;
  double wrms_north_mm_per_year = 0.0;
  std::string wrms_source;

  // The model's uncertainty for a point carried `years` by it: the
  // horizontal WRMS over that time, metres (issue 13: an epoch change by a
  // plate model is never stated as exact).
  double motion_uncertainty_m(double years) const;

  // The plate's velocity at x, in m/yr.
  Eigen::Vector3d velocity_m_per_year(const EcefPosition& x) const;
};

// Every parameter set in the catalog (each listed once, in its published
// direction).
const std::vector<CatalogTransformation>& catalog_transformations();
const std::vector<PlateMotionModel>& plate_motion_models();

// The model for `plate` in `frame`, or nullopt.
std::optional<PlateMotionModel> find_plate_motion_model(std::string_view frame, std::string_view plate);

// One step of a path: an edge of the catalog, forward or reversed.
struct FramePathStep {
  const CatalogTransformation* edge = nullptr;
  bool reverse = false;
  std::string_view from() const { return reverse ? edge->to : edge->from; }
  std::string_view to() const { return reverse ? edge->from : edge->to; }
  // to-frame ECEF of from-frame ECEF x at observation epoch t.
  EcefPosition apply(const EcefPosition& x, DecimalYear t) const;
};

struct FramePath {
  std::string from, to;
  std::vector<FramePathStep> steps;  // empty when from == to
  bool time_dependent() const;  // any step is
  // The stated accuracies of the steps combined as independent errors (root
  // sum of squares), metres.
  double accuracy_m() const;
  EcefPosition apply(const EcefPosition& x, DecimalYear t) const;
  // The whole path at epoch t as one affine map.
  AffineMap at(DecimalYear t) const;
  // One line per step: "ITRF2014 → ITRF2020 (reverse of ITRF2020 → ITRF2014), ±0.001 m: IERS …".
  std::string describe() const;
};

// The path with the fewest steps between two frames named as
// Frame::name() prints them (ties: the smaller combined accuracy). Throws
// geoanchor::Error (input) naming `where` for a frame the catalog does not
// know (listing those it does) or two frames it cannot connect.
FramePath find_frame_path(std::string_view from, std::string_view to, std::string_view where);

// A position and optionally its velocity (ECEF, m and m/yr).
struct StateVector {
  EcefPosition x;
  std::optional<Eigen::Vector3d> v_m_per_year;
};

// Coordinates in frame `from` at epoch t_from to frame `to` at epoch t_to,
// set up once (paths found, maps composed) and applied per point:
//  1. a point with a velocity: the path at t_from, then x += v·(t_to − t_from)
//     in `to`; the velocity is carried (v_to = dx_to/dt along the path);
//  2. otherwise, with a plate model: the path to the model's frame at
//     t_from, the plate's motion over t_to − t_from there, the path to `to`
//     at t_to;
//  3. otherwise t_to must equal t_from.
class FrameEpochTransform {
 public:
  // `path` from find_frame_path; `plate` may be null and must outlive this
  // object. Throws as find_frame_path (for the paths to and from the plate
  // model's frame).
  FrameEpochTransform(FramePath path, DecimalYear t_from, DecimalYear t_to, const PlateMotionModel* plate,
                      std::string_view where);

  const FramePath& path() const { return path_; }
  // Throws geoanchor::Error (input) naming `where` when the epochs differ
  // and the point has no velocity and there is no plate model.
  StateVector apply(const StateVector& in, std::string_view where) const;

 private:
  FramePath path_;
  DecimalYear t_from_, t_to_;
  AffineMap at_from_, ahead_, behind_;  // the path at t_from, t_from + 1 yr, t_from − 1 yr
  const PlateMotionModel* plate_;
  std::optional<AffineMap> to_plate_frame_, from_plate_frame_;  // at t_from and at t_to
};

// The frame names the catalog knows, sorted.
std::vector<std::string> catalog_frame_names();

}  // namespace geoanchor::geodesy
