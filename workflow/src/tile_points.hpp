#pragma once
// The extent of a tile's or vector map's points as read from the file itself
// (private to workflow): audit compares it with what the sidecar records and
// builds the seams from it, so that a tile changed after apply is found by
// its points, not by its metadata (issue 40 point 6).

#include <Eigen/Core>

#include <filesystem>
#include <optional>
#include <string>
#include <utility>

#include "geoanchor/io/tile/point_chain.hpp"

namespace geoanchor::workflow::detail {

// The smallest and largest coordinate of the points of `file` (a LAS, LAZ,
// CSV or PLY tile, a GeoJSON, Lanelet2 OSM or OpenDRIVE map) in the file's
// axes, as apply records them in provenance.bounds: every point read through
// the reader apply uses, in `coordinates` (the sidecar's), and moved nowhere.
// `local_xy`: a Lanelet2 map's local projection of its local_x/local_y
// tags, as apply recorded it (provenance.osm.local_xy.projection).
// Throws geoanchor::Error naming the file where it cannot be read.
std::pair<Eigen::Vector3d, Eigen::Vector3d> point_extent(const std::filesystem::path& file, const io::ArrayFrame& coordinates,
                                                         const std::optional<std::string>& local_xy);

}  // namespace geoanchor::workflow::detail
