#pragma once
// `geoanchor transform`: the epochs a frame path is evaluated at and what
// carries the points between them (velocity columns, a plate motion model,
// or --assume-zero-velocity), checked against what the options say.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/frame_catalog.hpp"
#include "geoanchor/geodesy/units.hpp"
#include "transform_command.hpp"

namespace geoanchor::cli {

struct TransformEpochs {
  bool from_dynamic = false, to_dynamic = false;
  std::vector<std::string> notes;  // flags given but not used
  std::optional<std::string> zero_velocity_note;  // the --assume-zero-velocity statement, when it moved an epoch
  // The epochs the path and the motion use; the ones the user stated are
  // what the output records (a static frame's under the assumption).
  geodesy::DecimalYear t_from, t_to;
  bool epochs_given = false;
  geodesy::DecimalYear stated_from, stated_to;
  std::optional<geodesy::PlateMotionModel> plate;  // the epoch change's, when a plate carries it

  // A static frame is named without an epoch when none was given.
  std::string frame_text(const geodesy::Frame& f, geodesy::DecimalYear t) const;
};

// Throws geoanchor::Error (usage) for an epoch missing or contradicted, an
// epoch change nothing carries, or two ways given to carry it.
TransformEpochs plan_transform_epochs(const TransformOptions& o, const geodesy::Frame& from, const geodesy::Frame& to,
                                      const geodesy::FramePath& path, bool has_velocity);

}  // namespace geoanchor::cli
