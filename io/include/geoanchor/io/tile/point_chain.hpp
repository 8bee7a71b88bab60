#pragma once
// A coordinate pipeline for many points: input frame -> ECEF -> optional
// transform -> ECEF -> output frame (the chain `apply` runs on tiles).
//
// When every step is affine — ECEF, ENU and NED at fixed origins, a Helmert
// or enu-origin transform at a fixed epoch — the chain is composed once, in
// long double, into one float64 affine map and applied with a plain loop.
// When only the output is geodetic or projected, the affine part is fused
// and ECEF -> geodetic runs over whole arrays (geodesy/geocentric_batch.hpp).
// Other geodetic and projected steps and site calibrations run point by
// point through the same code `convert` uses.

#include <optional>
#include <span>

#include "geoanchor/crs/array_frame.hpp"
#include "geoanchor/geodesy/affine.hpp"
#include "geoanchor/io/control/coordinate_codec.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::io {

// What one PointChain call met besides numbers: the first point a
// projection refused (its output is NaN: the caller refuses the tile, with
// this reason) and the points a UTM zone holds outside its band.
struct ChainReport {
  std::optional<std::size_t> first_refused;  // index in the arrays
  std::string refusal;                       // why, with the point and the projection's domain
  UtmBandTally input_band, output_band;      // worst_index: in the arrays
};

class PointChain {
 public:
  // Throws geoanchor::Error (usage) when a frame lacks its origin or
  // projection, or a time-dependent transform has no epoch.
  PointChain(const ArrayFrame& from, const std::optional<TransformFile>& transform, bool inverse,
             std::optional<geodesy::DecimalYear> epoch, const ArrayFrame& to);

  // The fused map when the whole chain is affine.
  const std::optional<geodesy::AffineMap>& fused() const { return fused_; }

  // Transforms the points (a[i], b[i], c[i]) in place: x,y,z | lat,lon,h
  // (degrees) | e,n,u | n,e,d | easting,northing,h. A point outside a
  // projection's domain (geodesy/projection.hpp) becomes NaN, and the
  // report says which and why; the caller must refuse non-finite output.
  ChainReport apply(std::span<double> a, std::span<double> b, std::span<double> c) const;

  // The same with a time-dependent transform evaluated at each point's own
  // epoch (decimal years, e.g. from LAS GPS time). Affine chains are built
  // at the earliest and latest epoch of the call and interpolated per
  // point: a 14-parameter Helmert is linear in time, up to the product of
  // scale and rotation rates (below 1e-12 m per year² at Earth radius).
  // Other transforms ignore `epochs`.
  ChainReport apply_at_epochs(std::span<double> a, std::span<double> b, std::span<double> c,
                              std::span<const double> epochs) const;

 private:
  geodesy::EcefPosition to_ecef(double a, double b, double c, std::size_t i, ChainReport& report) const;
  void from_ecef(const geodesy::EcefPosition& x, double& a, double& b, double& c, std::size_t i,
                 ChainReport& report) const;
  // Easting, northing of a geodetic point on the output projection (NaN
  // when refused, noted in `report`).
  void project(double lat_deg, double lon_deg, double h_m, double& a, double& b, double& c, std::size_t i,
               ChainReport& report) const;
  static std::optional<geodesy::AffineMap> affine_ecef_from(const ArrayFrame& f);  // frame -> ECEF, if affine
  void finish_from_output_ecef(std::span<double> a, std::span<double> b, std::span<double> c,
                               ChainReport& report) const;
  std::optional<geodesy::AffineMap> ecef_in_;   // input -> ECEF, when affine
  std::optional<geodesy::AffineMap> ecef_out_;  // output -> ECEF, when affine

  ArrayFrame from_, to_;
  std::optional<TransformFile> transform_;
  bool inverse_ = false;
  std::optional<geodesy::DecimalYear> epoch_;
  std::optional<geodesy::AffineMap> fused_;
  // When only the output step is not affine (geodetic, projected): the
  // affine part up to the output ECEF, then the array ECEF -> geodetic.
  std::optional<geodesy::AffineMap> to_output_ecef_;
  geodesy::GeocentricConverter from_geocentric_, to_geocentric_;
  std::optional<geodesy::LocalTangentPlane> from_plane_, to_plane_;
  std::optional<geodesy::TransverseMercator> from_tm_, to_tm_;
};

}  // namespace geoanchor::io
