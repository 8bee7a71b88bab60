// A transform file's model: its name, its rotation convention and how it is
// applied; the same transform without its fit record or in the other
// convention (what the reader's checks and the writer's alternatives use).

#include "geoanchor/io/transform/transform_file.hpp"

#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "geoanchor/base/error.hpp"
#include "transform/transform_common.hpp"

namespace geoanchor::io {

using geodesy::CoordinateFrame;
using geodesy::PositionVector;

std::string_view to_string(TransformModel m) {
  switch (m) {
    case TransformModel::helmert7: return "helmert7";
    case TransformModel::helmert6: return "helmert6";
    case TransformModel::translation3: return "translation3";
    case TransformModel::helmert14: return "helmert14";
    case TransformModel::molodensky_badekas: return "molodensky-badekas";
    case TransformModel::enu_origin: return "enu-origin";
    case TransformModel::site_calibration: return "site-calibration";
  }
  return "?";
}

std::string_view TransformFile::convention_name() const {
  return std::visit([](const auto& h) -> std::string_view {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<PositionVector>>) {
      return PositionVector::name;
    } else {
      return CoordinateFrame::name;
    }
  }, helmert);
}

geodesy::EcefPosition TransformFile::apply(const geodesy::EcefPosition& x,
                                           std::optional<geodesy::DecimalYear> observation_epoch, bool inverse,
                                           std::string_view where) const {
  if (site_calibration) return inverse ? site_calibration->source_from_target(x) : site_calibration->target_from_source(x);
  const geodesy::AffineMap m = target_from_source(observation_epoch, where);
  return geodesy::EcefPosition((inverse ? m.inverse() : m).apply(x.m));
}

geodesy::AffineMap TransformFile::target_from_source(std::optional<geodesy::DecimalYear> observation_epoch,
                                                     std::string_view where) const {
  if (site_calibration) {
    throw Error(ErrorKind::usage, "E_TRANSFORM", std::string(where) + ": a site calibration is not an affine map");
  }
  if (enu_origin) {
    return geodesy::enu_origin_correction(enu_origin->nominal, enu_origin->shift_enu_m, enu_origin->yaw, enu_origin->ds);
  }
  return std::visit([&](const auto& h) -> geodesy::AffineMap {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert14<PositionVector>> ||
                  std::is_same_v<H, geodesy::Helmert14<CoordinateFrame>>) {
      if (!observation_epoch) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    std::string(where) +
                        ": no observation epoch for a 14-parameter (time-dependent) transform; give --epoch YEAR or an "
                        "epoch column (the reference epoch " +
                        geodesy::format_decimal_year(h.reference_epoch) + " is never substituted)");
      }
      return geodesy::target_from_source(geodesy::evaluate_at(h, *observation_epoch), rotation_model);
    } else {
      const geodesy::AffineMap m = geodesy::target_from_source(h, rotation_model);
      if (!pivot_m) return m;
      // p + T + L (x − p) = L x + (T + p − L p)
      return geodesy::AffineMap(m.linear(), m.translation_m() + *pivot_m - m.linear() * *pivot_m);
    }
  }, helmert);
}

namespace detail {

// The transform without its fit record, member by member: a fit of 10⁶
// marks holds 10⁶ point records, and copying them only to drop them cost a
// second.
TransformFile without_fit_record(const TransformFile& t) {
  TransformFile out;
  out.model = t.model;
  out.rotation_model = t.rotation_model;
  out.helmert = t.helmert;
  out.source_frame = t.source_frame;
  out.target_frame = t.target_frame;
  out.reference_epoch = t.reference_epoch;
  out.pivot_m = t.pivot_m;
  out.enu_origin = t.enu_origin;
  out.site_calibration = t.site_calibration;
  return out;
}

// The same transform in the other rotation convention (no fit record).
TransformFile swapped_convention(const TransformFile& t) {
  TransformFile out = without_fit_record(t);
  std::visit([&](const auto& h) {
    using H = std::decay_t<decltype(h)>;
    if constexpr (std::is_same_v<H, geodesy::Helmert7<PositionVector>> || std::is_same_v<H, geodesy::Helmert14<PositionVector>>) {
      out.helmert = geodesy::to_coordinate_frame(h);
    } else {
      out.helmert = geodesy::to_position_vector(h);
    }
  }, t.helmert);
  return out;
}

}  // namespace detail

}  // namespace geoanchor::io
