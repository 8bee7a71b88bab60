#pragma once
// Where an artifact's points are (private to workflow's audit): its bounds
// as recorded and as read, in its coordinates' order, and the conversions
// to ECEF and to a local ENU that compare them.

#include <Eigen/Core>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/io/tile/point_chain.hpp"
#include "geoanchor/workflow/audit.hpp"

namespace geoanchor::workflow::audit_detail {

// One point of a tile's own coordinates in ECEF (no transform), and back.
std::optional<Eigen::Vector3d> to_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& p);
std::optional<Eigen::Vector3d> from_ecef(const io::ArrayFrame& f, const Eigen::Vector3d& x);

// The tile's bounds (output coordinates) from its provenance.
using Box = std::pair<Eigen::Vector3d, Eigen::Vector3d>;

// The bounds a sidecar records (provenance.bounds), in the file's axes.
std::optional<Box> recorded_bounds(const AuditArtifact& a);
// Bounds in the file's axes, in the order of the tile's coordinates.
std::optional<Box> in_coordinate_order(const AuditArtifact& a, Box box);
// The recorded bounds in the order of the tile's coordinates.
std::optional<Box> bounds_of(const AuditArtifact& a);
// Two extents of the same points (file axes) agree.
bool same_extent(const AuditArtifact& a, const Box& x, const Box& y);
std::string box_text(const Box& b);
// The eight corners of a box.
std::vector<Eigen::Vector3d> corners(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
// Residual of `x` against `ref` in ENU at `ref`.
Eigen::Vector3d enu_difference(const Eigen::Vector3d& ref, const Eigen::Vector3d& x);

}  // namespace geoanchor::workflow::audit_detail
