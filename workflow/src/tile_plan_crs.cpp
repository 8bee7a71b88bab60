// A tile in a CRS, or an output in one (--to-crs): PROJ's stages around
// geoanchor's chain, and the output's metadata in the CRS.
#include "geoanchor/workflow/tile_plan.hpp"

#include "geoanchor/base/error.hpp"
#include "tile_plan_frames.hpp"

namespace geoanchor::workflow {
namespace {

using detail::two_d;
using detail::with_epoch;
using io::ArrayFrame;
using io::TileMetadata;

}  // namespace

void TilePlanner::plan_crs_stages(TilePlan& p) const {
  const std::string tile = p.input.string();
  TileMetadata& in = p.in;
  TileMetadata& out = p.out;
  if (!o_.to_crs && (o_.origin || o_.zone || o_.tm || o_.ellipsoid)) {
    // The output stays in the tile's CRS, which these flags cannot change.
    throw Error(ErrorKind::usage, "E_OPTION",
                tile + ": the tile is in the CRS " + in.crs->display_name() + " (" + p.in_frame_source + "), so " +
                    (o_.origin ? "--origin" : o_.zone ? "--zone" : o_.tm ? "--tm" : "--ellipsoid") +
                    " says nothing about its output; give --to KIND (geoanchor's own coordinates) or --to-crs CRS");
  }
  io::Crs dst = o_.to_crs ? io::Crs::parse(*o_.to_crs, "--to-crs") : *in.crs;
  const std::string dst_flag = o_.to_crs ? "--to-crs " + *o_.to_crs : "the tile's CRS";
  // The file's heights: a 2-D input has none (Z passes unchanged, to a 2-D
  // output only); a 3-D input keeps them (a 2-D output CRS gets its
  // ellipsoidal height axis, as convert does).
  const bool in_2d = in.crs && two_d(*in.crs);
  if (in_2d && (!two_d(dst) || t_)) {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source +
                    ") is 2-D: its Z values are no heights PROJ can place; give --crs with the same CRS in 3-D or "
                    "compound (its heights), or a 2-D --to-crs without a transform (Z then passes unchanged)");
  }
  if (!in_2d && two_d(dst)) dst = dst.promoted_to_3d(dst_flag);
  if (in_2d) {
    // Z passes unchanged, so it must mean the same number on both sides: a
    // 2-D CRS states no unit for it (by custom a LAS tile's Z is in the
    // horizontal unit of a projected CRS and in metres beside degrees, but
    // nothing in the file says so), and a change of that unit would leave
    // feet in a tile in metres (issue 40 point 2).
    const auto z_unit = [](const io::Crs& c) -> std::pair<std::string, double> {
      const auto& d = c.description();
      const auto& axes = d.visualization_axes.empty() ? d.axes : d.visualization_axes;
      if (!axes.empty() && axes[0].unit_type == "linear") return {axes[0].unit_name, axes[0].unit_to_si};
      return {"metre", 1.0};
    };
    const auto [ui, si_in] = z_unit(*in.crs);
    const auto [uo, si_out] = z_unit(dst);
    if (si_in != si_out) {
      throw Error(ErrorKind::input, "E_HEIGHT_UNIT",
                  tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source + ") is 2-D in " + ui +
                      " and " + dst_flag + " is 2-D in " + uo + ": the tile's Z values would pass unchanged from " +
                      ui + " into a file in " + uo + ", and no CRS states their unit; give --crs with the tile's CRS in 3-D or "
                      "compound (EPSG:h+v, its heights and their unit), so the heights are converted");
    }
    p.warnings.push_back(tile + ": the tile's CRS " + in.crs->display_name() +
                         " is 2-D: its Z values are no coordinate of it and were copied unchanged into the 2-D output");
  }
  if (!t_) {
    // A dynamic output CRS without its epoch is at the tile's: an operation
    // between realizations is evaluated at one epoch and keeps it.
    const auto in_epoch = in.crs ? in.crs->epoch() : in.frame->epoch();
    if (dst.description().dynamic && !dst.epoch() && in_epoch) dst = dst.at_epoch(*in_epoch, dst_flag);
    if (in.crs && io::is_las_family(p.format) && !o_.resolution_m && in.crs->same_as(dst)) {
      // The tile's own CRS: nothing moves, and the LAS integers, scale and
      // offset are kept (a LAS <-> LAZ conversion keeps every record).
      p.chain_used = false;
      p.keep_coordinates = true;
    } else if (in.crs) {
      p.before = std::make_pair(*in.crs, dst);  // PROJ's own operation between the two
      p.chain_used = false;
    } else {
      // geoanchor's coordinates to their frame's geocentric CRS, then PROJ.
      // A static frame's epoch records when its points were observed (as
      // geoanchor's outputs state ETRF2000@2024.5): no coordinate of its CRS.
      const io::Crs frame = io::Crs::parse(geodesy::is_dynamic(*in.frame) ? in.frame->to_string() : in.frame->name(),
                                           tile + ": the tile's frame");
      p.after = std::make_pair(frame.geocentric(tile), dst);
    }
  } else {
    if (in.crs) {
      p.before = std::make_pair(*in.crs, in.crs->geocentric(tile));
      in.coordinates = ArrayFrame{};
    }
    if (!o_.to_crs) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  tile + ": the tile is in " + in.crs->display_name() + " and the transform moves it into " +
                      out.frame->to_string() + ": give the output's CRS (--to-crs) or kind (--to)");
    }
    const auto& d = dst.description();
    if (d.catalog_frame != out.frame->name()) {
      throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                  tile + ": " + dst_flag + " is on datum '" + d.datum + "'" +
                      (d.catalog_frame.empty() ? "" : " (" + d.catalog_frame + ")") + " but the transform's output is in " +
                      out.frame->to_string() + ": give a CRS on that frame (e.g. " + out.frame->name() +
                      "), or move the output on with a second apply");
    }
    if (d.dynamic) {
      const auto& fe = out.frame->epoch();
      if (dst.epoch() && fe && dst.epoch()->year != fe->year) {
        throw Error(ErrorKind::input, "E_CRS_EPOCH",
                    tile + ": " + dst_flag + " is at epoch " + geodesy::format_decimal_year(*dst.epoch()) +
                        " but the transform's output is at " + geodesy::format_decimal_year(*fe) +
                        ": a transform does not move points in time");
      }
      // Per-point epochs (--epoch-from-gps-time) leave the output without
      // one epoch: the conversion to the CRS needs none.
      const bool per_point = o_.epoch_from_gps_time && io::is_las_family(p.format);
      if (per_point && dst.epoch()) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    tile + ": " + dst_flag + " names the epoch " + geodesy::format_decimal_year(*dst.epoch()) +
                        " but --epoch-from-gps-time leaves each point at its own GPS time; give the CRS without it");
      }
      if (!dst.epoch() && !fe && !per_point) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    tile + ": " + dst_flag + " is dynamic and the transform's output has no coordinate epoch; give "
                                             "--to-crs CRS@EPOCH");
      }
      if (!dst.epoch() && fe) dst = dst.at_epoch(*fe, dst_flag);
    }
    p.after = std::make_pair(dst.geocentric(dst_flag), dst);
  }
  // The output in the CRS (its coordinates ECEF between the stages), with
  // the tile's survey record; a static frame keeps the epoch of its
  // coordinates' observation, as geoanchor's own outputs record it
  // (ETRF2000@2024.5).
  io::TileMetadata in_crs = io::tile_metadata_from_crs(dst, tile);
  if (out.frame && in_crs.frame && !in_crs.frame->epoch()) {
    // A static output frame (ETRF2000, GDA2020) is labelled with the
    // epoch its points were observed at, as the input states it.
    if (out.frame->name() == in_crs.frame->name()) {
      in_crs.frame = out.frame;
    } else if (out.frame->epoch()) {
      in_crs.frame = with_epoch(*in_crs.frame, *out.frame->epoch());
    }
  }
  in_crs.storage = out.storage;
  in_crs.survey_method = out.survey_method;
  in_crs.rtk_fixed_percent = out.rtk_fixed_percent;
  out = std::move(in_crs);
}

}  // namespace geoanchor::workflow
