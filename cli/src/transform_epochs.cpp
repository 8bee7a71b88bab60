// `geoanchor transform`: the epochs of the frame path and what carries the
// points between them (transform_epochs.hpp).
#include "transform_epochs.hpp"

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::cli {
namespace {

using geodesy::DecimalYear;

// The plates of a plate motion model, for messages: all of them, since
// geoanchor does not know which plate the points are on.
std::string plate_list(const std::string& model) {
  std::string list;
  for (const auto& m : geodesy::plate_motion_models()) {
    if (m.frame == model) list += (list.empty() ? "" : ", ") + m.plate;
  }
  return (list.empty() ? std::string("none") : list) + " in the " + model + " model";
}

// The epochs the two sides name. A dynamic frame's coordinates change with
// time; a static (plate-fixed) frame's move too, by the intraplate
// velocities (a few mm/yr, up to 3 cm/yr in the western US), so an epoch
// asked for on a static side is honoured like any other: the points move by
// their velocities (or the plate model) in the source frame and the
// time-dependent path is evaluated at the target epoch, as HTDP does
// (issue 40 point 1). Where a side names no epoch, the other side's is
// used (issue 13 point 4): a static frame needs no epoch of its own.
struct NamedEpochs {
  std::optional<DecimalYear> from, to;
};

NamedEpochs named_epochs(const TransformOptions& o, const geodesy::Frame& from, const geodesy::Frame& to,
                         const geodesy::FramePath& path, bool from_dynamic, bool to_dynamic) {
  std::optional<DecimalYear> from_epoch = from.epoch(), to_epoch = to.epoch();
  if (!from_dynamic && to_dynamic && to_epoch && !from_epoch) from_epoch = to_epoch;
  if (from_dynamic && !to_dynamic && from_epoch && !to_epoch) to_epoch = from_epoch;
  if (to_epoch && !from_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                "--from " + o.from + ": --to names an epoch, so the input's epoch is needed too, e.g. " + from.name() + "@2010.0");
  }
  if (path.time_dependent() && !from_epoch) {
    throw Error(ErrorKind::usage, "E_EPOCH_MISSING",
                "--from " + o.from + ": the transformation " + from.name() + " → " + to.name() +
                    " is time-dependent: give the coordinates' epoch, e.g. " + from.name() + "@2010.0" +
                    (from_dynamic || to_dynamic ? "" : ", or the epoch of a dynamic frame on the other side"));
  }
  return NamedEpochs{from_epoch, to_epoch};
}

// --assume-zero-velocity: the points stand still in the plate-fixed
// frame, so the path is evaluated at the dynamic side's epoch and the
// static side's coordinates hold at any epoch. Refused where that says
// nothing (two dynamic frames) or cannot hold (two static frames joined
// through the ITRF, whose plates differ). Moves the static side's epoch to
// the dynamic side's and returns the statement that says so; a note in
// `e` when there is no epoch change to carry.
std::optional<std::string> assume_zero_velocity(const TransformOptions& o, const geodesy::Frame& from, const geodesy::Frame& to,
                                                const geodesy::FramePath& path, bool has_velocity, NamedEpochs& epochs,
                                                TransformEpochs& e) {
  std::optional<DecimalYear>& from_epoch = epochs.from;
  std::optional<DecimalYear>& to_epoch = epochs.to;
  const bool from_dynamic = e.from_dynamic, to_dynamic = e.to_dynamic;
  const bool epoch_change = from_epoch && to_epoch && from_epoch->year != to_epoch->year;
  std::optional<std::string> zero_velocity_note;
  if (has_velocity || o.plate) {
    throw Error(ErrorKind::usage, "E_OPTION",
                std::string("--assume-zero-velocity with ") + (has_velocity ? "the input's velocity columns" : "--plate") +
                    ": give one way to carry the points between epochs");
  }
  if (from_dynamic && to_dynamic) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--assume-zero-velocity: " + from.name() + " and " + to.name() + " are both dynamic frames, in which "
                "points move with their plates; give velocity columns or --plate");
  }
  if (!from_dynamic && !to_dynamic && epoch_change && path.time_dependent()) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--assume-zero-velocity: " + from.name() + " and " + to.name() + " are both plate-fixed and joined by a "
                "time-dependent path, so points cannot stand still in both; give velocity columns");
  }
  if (epoch_change) {
    const DecimalYear used = from_dynamic ? *from_epoch : *to_epoch;
    const geodesy::Frame& fixed = from_dynamic ? to : from;
    const DecimalYear fixed_epoch = from_dynamic ? *to_epoch : *from_epoch;
    zero_velocity_note = "--assume-zero-velocity: the points are assumed not to move in the plate-fixed frame " +
                         fixed.name() + " between " + geodesy::format_decimal_year(fixed_epoch) + " and " +
                         geodesy::format_decimal_year(used) + " (no intraplate velocity); the path is evaluated at " +
                         geodesy::format_decimal_year(used) + ". Where the points do move in " + fixed.name() +
                         " (mm to cm a year), the result is off by that motion";
    if (from_dynamic) {
      to_epoch = from_epoch;
    } else {
      from_epoch = to_epoch;
    }
  } else {
    e.notes.push_back("--assume-zero-velocity not used: the coordinates stay at epoch " +
                      (from_epoch ? geodesy::format_decimal_year(*from_epoch) : std::string("(none)")));
  }
  return zero_velocity_note;
}

// --plate: its model, checked even when not used (an unknown plate is a
// typo); none when the epochs are the same.
std::optional<geodesy::PlateMotionModel> plate_motion(const TransformOptions& o, DecimalYear t_from, DecimalYear t_to) {
  std::optional<geodesy::PlateMotionModel> plate;
  if (o.plate) {  // checked even when not used: an unknown plate is a typo
    if (o.plate_model != "ITRF2020" && o.plate_model != "ITRF2014") {
      throw Error(ErrorKind::usage, "E_OPTION", "--plate-model " + o.plate_model + ": expected ITRF2020 or ITRF2014");
    }
    plate = geodesy::find_plate_motion_model(o.plate_model, *o.plate);
    if (!plate) {
      throw Error(ErrorKind::usage, "E_OPTION", "--plate " + *o.plate + ": expected a plate: " + plate_list(o.plate_model));
    }
    if (t_from.year == t_to.year) plate.reset();
  }
  return plate;
}

// An epoch change needs one thing that carries the points: velocity
// columns or a plate, not both.
void require_one_motion(const TransformOptions& o, const geodesy::Frame& from, const geodesy::Frame& to, bool has_velocity,
                        const TransformEpochs& e) {
  const DecimalYear t_from = e.t_from, t_to = e.t_to;
  const bool from_dynamic = e.from_dynamic, to_dynamic = e.to_dynamic;
  const auto& plate = e.plate;
  if (t_to.year != t_from.year && !has_velocity && !plate) {
    throw Error(ErrorKind::usage, "E_EPOCH_PROPAGATION",
                "--to " + o.to + ": moving coordinates from " + geodesy::format_decimal_year(t_from) + " to " +
                    geodesy::format_decimal_year(t_to) +
                    " needs velocities (columns vx_m_per_year, vy_m_per_year, vz_m_per_year, or ve_m_per_year, "
                    "vn_m_per_year, vu_m_per_year) or a plate motion model: "
                    "--plate PLATE, the plate the points are on (" + plate_list(o.plate_model) + ")" +
                    (from_dynamic != to_dynamic
                         ? std::string("; points move in the plate-fixed frame ") + (from_dynamic ? to : from).name() +
                               " too (intraplate velocities, mm to cm a year): --assume-zero-velocity assumes they do not"
                         : std::string()));
  }
  if (has_velocity && plate) {
    throw Error(ErrorKind::usage, "E_OPTION", "--plate: the input has velocity columns; give one or the other");
  }
}

}  // namespace

std::string TransformEpochs::frame_text(const geodesy::Frame& f, DecimalYear t) const {
  return epochs_given && (geodesy::is_dynamic(f) || f.epoch()) ? f.name() + "@" + geodesy::format_decimal_year(t) : f.name();
}

TransformEpochs plan_transform_epochs(const TransformOptions& o, const geodesy::Frame& from, const geodesy::Frame& to,
                                      const geodesy::FramePath& path, bool has_velocity) {
  TransformEpochs e;
  e.from_dynamic = geodesy::is_dynamic(from), e.to_dynamic = geodesy::is_dynamic(to);
  NamedEpochs epochs = named_epochs(o, from, to, path, e.from_dynamic, e.to_dynamic);
  if (o.assume_zero_velocity) e.zero_velocity_note = assume_zero_velocity(o, from, to, path, has_velocity, epochs, e);
  const std::optional<DecimalYear>& from_epoch = epochs.from;
  const std::optional<DecimalYear>& to_epoch = epochs.to;
  e.t_from = from_epoch.value_or(DecimalYear{2000.0});  // a static path ignores it
  e.t_to = to_epoch.value_or(e.t_from);
  e.epochs_given = from_epoch.has_value();
  e.stated_from = from.epoch().value_or(e.t_from), e.stated_to = to.epoch().value_or(e.t_to);
  if (o.plate && e.t_from.year == e.t_to.year) {
    e.notes.push_back("--plate " + *o.plate + " not used: the coordinates stay at epoch " + geodesy::format_decimal_year(e.t_from));
  }
  e.plate = plate_motion(o, e.t_from, e.t_to);
  require_one_motion(o, from, to, has_velocity, e);
  return e;
}

}  // namespace geoanchor::cli
