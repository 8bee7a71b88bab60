#pragma once
// What the CSV and JSON control-set readers share: turning one frame's
// coordinates and uncertainty into ECEF, and the duplicate-id rule.

#include <Eigen/Core>

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/io/control/coordinate_columns.hpp"
#include "geoanchor/io/control/crs_columns.hpp"

namespace geoanchor::io::detail {

// One frame's values for one point, as read.
struct RoleValues {
  CoordinateKind kind = CoordinateKind::ecef;
  double a = 0.0, b = 0.0, c = 0.0;              // x,y,z | lat,lon,h | e,n,u
  std::optional<double> sigma_m;                 // isotropic
  std::optional<std::array<double, 6>> cov_m2;   // xx, xy, xz, yy, yz, zz in the coordinates' axes
  bool source = true;                            // which frame (for its projection and geoid)
  bool orthometric = false;                      // geodetic, projected: c is H, read as h = H + N
};

// Which value a failure is about: the three coordinates, the sigma, the covariance.
enum class RoleField { first, second, third, sigma, covariance };
using RoleFail = std::function<void(RoleField, const std::string& message)>;  // throws

// Each frame's ellipsoid by the rule of ControlReadOptions::ellipsoid, into
// the set's input forms; `uses_ellipsoid[k]`: role k (source, target) has
// geodetic, projected or ENU values. Throws geoanchor::Error (usage,
// E_ELLIPSOID) for --ellipsoid that contradicts such a role's frame.
void resolve_ellipsoids(geodesy::ControlSet& set, const ControlReadOptions& o, const bool uses_ellipsoid[2]);

// The caller's frames into the set (CallerFrame: replace, else the file's,
// else fallback).
void apply_caller_frames(geodesy::ControlSet& set, const ControlReadOptions& o);

// A frame whose values are in a CRS: its input form (crs, name, heights)
// and its frame, the CRS's catalog frame (a frame the file names must be
// the same, E_FRAME_CONFLICT naming both). `where` names the flag or key.
void adopt_crs(geodesy::ControlSet& set, bool source, const CrsColumns& columns, const std::string& where);

// That frame's values as read (as_read: the CRS's numbers in visualisation
// order and units) to ECEF on the CRS's datum through PROJ, a batch at a
// time. A covariance given in the CRS's axes (m² along each axis: ground
// metres along a latitude or longitude axis, grid metres along a projected
// one) is carried by the Jacobian of that conversion, taken by central
// differences through PROJ, for the points `has_covariance` names; an
// isotropic sigma needs none. Errors name a point by `name`.
void positions_from_crs(geodesy::ControlSet& set, bool source, const CrsColumns& columns, const std::string& where,
                        const std::function<bool(std::size_t)>& has_covariance,
                        const std::function<std::string(const geodesy::ControlPoint&)>& name);

class RoleConverter {
 public:
  // With the ellipsoids resolve_ellipsoids put into `set`'s input forms.
  RoleConverter(const ControlReadOptions& options, const geodesy::ControlSet& set);
  // Position and ECEF covariance; `others_have_sigmas`: the set gives sigmas
  // somewhere, so a frame without them carries no uncertainty. Returns the
  // geoid undulation N added to an orthometric height (0 otherwise); a
  // point outside the geoid's grid fails on the third value.
  double convert(const RoleValues& v, bool others_have_sigmas, const RoleFail& fail, geodesy::EcefPosition& position,
                 Eigen::Matrix3d& cov_m2) const;

 private:
  ControlReadOptions options_;
  geodesy::GeocentricConverter src_geocentric_, dst_geocentric_;
  std::optional<geodesy::LocalOrigin> src_origin_, dst_origin_;  // on each frame's ellipsoid
  std::optional<geodesy::LocalTangentPlane> src_plane_, dst_plane_;
  std::optional<geodesy::TransverseMercator> src_grid_, dst_grid_;
};

// The form of one frame's coordinates as the set records it; `height_column`
// non-empty: its heights were orthometric, read on `geoid`.
geodesy::ControlInputForm input_form(CoordinateKind kind, const std::optional<geodesy::ProjectionDef>& projection,
                                     const std::string& height_column = {}, const geodesy::GeoidGrid* geoid = nullptr);

// The refusal of an orthometric height without its geoid, naming `where`
// (the column or JSON key).
[[noreturn]] void refuse_orthometric_without_geoid(const std::string& where);

// Refuses a dynamic frame of `set` that names no coordinate epoch while a
// point has none either (geodesy::require_epoch_if_dynamic), naming where
// each frame was declared (empty: not declared in the file).
// A frame the caller overrides (ControlReadOptions) is not checked.
// Every mark's source and target lie on the Earth (issue 40 point 10):
// Error (input, E_ECEF_RANGE) naming `where(point)` and the role otherwise.
void check_physical_positions(const geodesy::ControlSet& set, const std::function<std::string(const geodesy::ControlPoint&)>& where);

void check_frame_epochs(const geodesy::ControlSet& set, const ControlReadOptions& o, const std::string& source_where,
                        const std::string& target_where);

// Refuses a set in which an id occurs twice at the same epoch, naming the
// first repeat in file order (`where_new`: file:line or JSON path) and the
// point it repeats (`where_of`). One sort after reading, not a map lookup a
// row: 10⁶ rows read in about a second.
void refuse_duplicate_ids(const geodesy::ControlSet& set,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_new,
                          const std::function<std::string(const geodesy::ControlPoint&)>& where_of);

}  // namespace geoanchor::io::detail
