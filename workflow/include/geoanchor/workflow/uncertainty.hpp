#pragma once
// The uncertainty a transform file gives a transformed position: what
// `apply` records for each tile (its worst bounding-box corner) and what the
// workbench can show. The file's sigmas and correlation are the parameters'
// covariance Σθ (validated when the file is read: io/transform/transform_file.hpp);
// the Jacobian is taken by central differences of ±σ on each parameter as
// the file spells it, so every model (Helmert, Molodensky-Badekas,
// enu-origin, site-calibration; forward or inverse) is covered by the one
// code path that also applies the transform.

#include <Eigen/Core>

#include <optional>

#include "geoanchor/geodesy/positions.hpp"
#include "geoanchor/geodesy/units.hpp"
#include "geoanchor/io/transform/transform_file.hpp"

namespace geoanchor::workflow {

// The covariance (ECEF, m²) that the fitted parameters' uncertainty gives
// the transformed position of `x` (J Σθ Jᵀ, J by central differences of
// width σ on each parameter, Σθ from the file's sigmas and correlation; the
// identity correlation only when the record says `uncorrelated`).
// std::nullopt when the file carries no sigmas; NaN in every entry for a
// record whose correlation does not cover a sigma'd parameter (only a record
// built in code can be so: the reader refuses it).
std::optional<Eigen::Matrix3d> propagated_covariance_m2(const io::TransformFile& t, const geodesy::EcefPosition& x,
                                                        std::optional<geodesy::DecimalYear> epoch, bool inverse);

}  // namespace geoanchor::workflow
