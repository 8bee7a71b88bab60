#pragma once
// The map metadata contract (io/map_metadata.hpp) of what `apply` writes:
// filled from the output's own coordinates, the input's metadata, the
// points' GNSS solution types (LAS extra bytes "gnss_solution") and the
// survey-metadata file (apply --survey-metadata), each checked against the
// others (docs/tile-metadata.md#the-map-metadata-contract).

#include <optional>
#include <string>

#include "geoanchor/io/map_metadata.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"

namespace geoanchor::workflow {

struct TilePlan;

// The survey file read against the input: its frame and epoch, ENU origin,
// its source and vertical datum must be what the input states (`in`, read
// from `in_source`: "sidecar t.las.geoanchor.json", "LAS WKT", …).
// Throws geoanchor::Error (input, E_METADATA_CONFLICT) naming both.
void check_survey_against_input(const io::SurveyMetadata& survey, const io::TileMetadata& in, const std::string& in_source,
                                const std::string& artifact);

// The contract of an output whose own metadata is `out` (frame,
// coordinates, storage, horizontal_crs, vertical keys, as written beside
// it), made from input `in` (read from `in_source`):
//   - derived: frame and epoch (or `epoch_range`, per-point epochs), the
//     ENU origin of ENU/NED coordinates, horizontal_crs, vertical datum,
//     the geoid of orthometric heights, the storage;
//   - computed: the RTK-fixed share and counts from `solution_counts`
//     (LAS extra bytes), when given;
//   - carried from the input: its metadata's GNSS method and base, geoid,
//     share and counts, and, while the frame is the same, its ENU origin
//     (and the origin's source when the output keeps that origin);
//     survey.rtk_fixed_percent of a /1 sidecar;
//   - the survey file's fields (those bound to its frame only while the
//     output is in the input's frame).
// Values stated twice must agree (a stated share with the computed one to
// its rounding): E_METADATA_CONFLICT otherwise.
io::MapMetadata output_map_metadata(const io::TileMetadata& out, const io::TileMetadata& in, const std::string& in_source,
                                    const std::optional<std::array<double, 2>>& epoch_range,
                                    const std::optional<std::array<std::uint64_t, 7>>& solution_counts,
                                    const io::SurveyMetadata* survey, const std::string& artifact);

}  // namespace geoanchor::workflow
