#pragma once
// The workbench's colours, chosen for readers with colour-vision deficiency:
// categorical colours from Okabe & Ito (2008, "Color Universal Design"), and
// ColorBrewer's PuOr diverging scheme (Brewer, colorbrewer2.org, marked
// colour-blind safe) for signed quantities — vertical residuals and
// correlations. Meaning never rests on colour alone: outliers are also a
// square, thick and labelled; left-out points are hollow and labelled.

#include "geoanchor/gui/image.hpp"

namespace geoanchor::gui::palette {

inline constexpr Rgb kBackground{255, 255, 255};
inline constexpr Rgb kPanel{246, 246, 246};
inline constexpr Rgb kInk{25, 25, 25};           // text, used points' arrows, the normal curve
inline constexpr Rgb kOutlier{213, 94, 0};       // Okabe–Ito vermillion: outliers, failed tests
inline constexpr Rgb kBar{86, 180, 233};         // Okabe–Ito sky blue: histogram bars
inline constexpr Rgb kCritical{204, 121, 167};   // Okabe–Ito reddish purple: critical values
inline constexpr Rgb kPass{0, 158, 115};         // Okabe–Ito bluish green: passed tests
inline constexpr Rgb kWarning{230, 159, 0};      // Okabe–Ito orange: w-tests near their critical value
inline constexpr Rgb kLeftOut{140, 140, 140};    // points the user left out
inline constexpr Rgb kEllipse{0, 114, 178};      // Okabe–Ito blue: residual ellipses
inline constexpr Rgb kGrid{215, 215, 215};

// PuOr at t in [−1, 1]: −1 purple (#5e3c99), 0 near-white (#f7f7f7), +1
// orange (#e66101), through ColorBrewer's 5-class stops; t is clamped.
Rgb diverging(double t);

}  // namespace geoanchor::gui::palette
