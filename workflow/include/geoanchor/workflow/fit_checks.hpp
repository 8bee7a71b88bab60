#pragma once
// What `fit` (and the workbench's Save transform…) check around a fit: the
// control set before it (frames, quantized coordinates, swapped axes, heights
// absorbed by the vertical offset) and the result after it (written, or
// refused and why). The same checks for both faces, so that a transform the
// command refuses cannot be saved from the window either.

#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/control_point.hpp"
#include "geoanchor/geodesy/geoid.hpp"
#include "geoanchor/solver/helmert_fit.hpp"

namespace geoanchor::workflow {

// Warnings about the control set itself:
//  - a frame that is the WGS 84 ensemble (its realizations differ by up to
//    about 2 m);
//  - a frame whose ECEF values as read are all float32 values (quantized to
//    0.25–0.5 m): its residuals are quantization, not blunders.
std::vector<std::string> control_set_warnings(const geodesy::ControlSet& set);

// The epoch a fit of fixed parameters (every model but helmert14) holds at,
// when a frame of the set is dynamic and names none because every point
// has its own epoch: the used marks' mean epoch, which the transform file then
// names (its reader refuses a dynamic frame without one). nullopt when no
// frame needs it. Throws Error (input, E_EPOCH_SPREAD) when the used marks'
// epochs span more than kCampaignSpread_yr: a fixed transform fitted across
// years of plate motion holds at no epoch (fit helmert14, or give the
// coordinates at one epoch).
inline constexpr double kCampaignSpread_yr = 0.1;  // ≈ 5 weeks: 7 mm at the fastest plate's 7 cm/yr
std::optional<geodesy::DecimalYear> fixed_fit_epoch(const geodesy::ControlSet& set, solver::FitModel model);

// The set's frames as the transform file names them: a dynamic frame
// without an epoch takes fixed_fit_epoch's.
std::optional<geodesy::Frame> written_frame(const std::optional<geodesy::Frame>& frame, const geodesy::ControlSet& set,
                                            solver::FitModel model);

// When the set's latitudes and longitudes look swapped in one frame: both
// frames are geodetic, the marks lie hundreds of kilometres apart as read,
// and reading one frame's columns the other way round brings them within a
// kilometre of each other. The message names the frame and the columns.
std::optional<std::string> likely_lat_lon_swap(const geodesy::ControlSet& set);

// One mark (or a few) whose source and target lie hundreds of kilometres
// apart while the others agree (issue 40 point 10): a row with latitude and
// longitude swapped, or a wrong unit, which would end the solve in "no
// convergence". The message names the first such mark, its line, how far
// apart its roles are against the marks' median, and which role reads
// close when its latitude and longitude are swapped.
std::optional<std::string> far_apart_mark(const geodesy::ControlSet& set);

// When the fitted transform's vertical offset looks like the geoid
// undulation: at the centroid of the marks the fit used, the displacement
// target − source along the local up (from the fitted parameters) is larger
// than kHeightTypeMinOffset_m and within max(kHeightTypeTolerance_m,
// kHeightTypeTolerance × |N|) of +N (source heights orthometric) or −N
// (target heights orthometric), N from `geoid` there
// (geodesy::geoid_along_up, as diagnose's height_type hypothesis). No datum
// shift between terrestrial frames moves heights by metres, and EGM96's N
// lies between −107 m and +85 m, so an offset of N's size and sign is a
// height type, not a datum. The message names the offset, N and the frame.
// Models whose source is ENU (enu-origin, site-calibration) are not checked.
inline constexpr double kHeightTypeMinOffset_m = 5.0;  // datum shifts: decimetres at most
inline constexpr double kHeightTypeTolerance_m = 1.0;  // a geoid model other than EGM96 differs by ≲ 1 m
inline constexpr double kHeightTypeTolerance = 0.1;    // and by ≲ 10 % of N where N is large
std::optional<std::string> orthometric_height_warning(const solver::FitResult& fit, const geodesy::ControlSet& set,
                                                      const geodesy::GeoidGrid& geoid);

// Why a fit must not be written, if it must not: the solver's own refusal
// (data snooping at its limit), else a global test that fails high unless
// `accept_failed_global_test`. `code` is the error code to report.
struct FitRefusal {
  std::string code;
  std::string message;
};
std::optional<FitRefusal> fit_refusal(const solver::FitResult& fit, const std::string& source_name,
                                      bool accept_failed_global_test);

}  // namespace geoanchor::workflow
