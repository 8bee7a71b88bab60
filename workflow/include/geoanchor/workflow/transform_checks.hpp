#pragma once
// What `convert` and `apply` check about the transform file they apply
// (issue 12 point 7, RELIABILITY #15): the same plausibility limits `fit`
// warns with (geodesy::implausible_parameter_warnings, one set of limits in
// geodesy/helmert.hpp), so that a file with rx = 20″, ds = 200 ppm or
// tx = 1e300 m is never applied silently.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/geodesy/units.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::workflow {

// The epochs a time-dependent transform is used at: the earliest and the
// latest (equal for a single epoch). The parameters are linear in time, so
// each is largest in magnitude at one end of the span: checking both ends
// checks every epoch in between.
struct EpochSpan {
  geodesy::DecimalYear first, last;
};

// One warning per implausible parameter, each starting with `transform_name`
// (the file as the user named it) and naming the parameter, its value, the
// limit and its effect at the Earth's surface:
//  - helmert7, helmert6, translation3, molodensky-badekas: the seven
//    parameters as stored (a Molodensky-Badekas translation is the shift at
//    its pivot, which the same 1 km limit bounds even more naturally);
//  - helmert14: the seven evaluated at both ends of `epochs_of_use`, each
//    warning naming its epoch ("T.json at epoch 2030.0: rx = ..."); nothing
//    when no epoch is given, since such a transform is never applied without
//    one (the reference epoch is not substituted);
//  - enu-origin and site-calibration: nothing. Their parameters place a local
//    map, not a geocentric frame: the origin shift is wherever the map was
//    anchored (kilometres), the yaw is whatever north the map was drawn
//    with, and a scale of some hundred ppm is what ground distances at a
//    site's height (≈157 ppm per kilometre of height) or odometry give. The
//    geodesy limits' reasoning (geocentric frames agree to arc-seconds and
//    ppm, so more is a wrong unit) does not apply to them.
// Non-finite parameters never get here: JSON has no NaN or infinity, and a
// number beyond double's range is refused when the file is read (E_JSON).
std::vector<std::string> implausible_transform_warnings(const io::TransformFile& t, std::string_view transform_name,
                                                        std::optional<EpochSpan> epochs_of_use);

}  // namespace geoanchor::workflow
