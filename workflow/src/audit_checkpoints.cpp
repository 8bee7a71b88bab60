// The checkpoints check of a map's audit: surveyed marks against the map's
// transform of their source positions.
#include <algorithm>
#include <cmath>

#include "audit_artifacts.hpp"
#include "audit_checks.hpp"
#include "audit_geometry.hpp"
#include "audit_text.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/io/control/control_csv.hpp"
#include "geoanchor/workflow/uncertainty.hpp"

namespace geoanchor::workflow::audit_detail {

AuditCheck check_checkpoints(const std::vector<AuditArtifact>& arts, const AuditRequest& request, Transforms& transforms) {
  const AuditLimits& l = request.limits;
  AuditCheck c = make_check("checkpoints",
                            "airside map accuracy: surveyed checkpoints against the map's transform of their source "
                            "positions",
                            "horizontal ≤ " + cm(l.checkpoint_horizontal_m) + " (--max-checkpoint-horizontal-m), vertical ≤ " +
                                cm(l.checkpoint_vertical_m) + " (--max-checkpoint-vertical-m)");
  if (!request.checkpoints) {
    c.status = AuditStatus::not_run;
    c.summary = "no --checkpoints given";
    return c;
  }
  io::ControlReadOptions read;
  read.origin = map_origin(arts);  // for ENU columns: the map's origin
  const geodesy::ControlSet set = request.checkpoints_dst
                                      ? io::read_control_pair(*request.checkpoints, *request.checkpoints_dst, read)
                                      : io::read_control_set(*request.checkpoints, read);
  // The map's moves: one for the whole map, or the tile's whose bounds hold the mark.
  std::vector<std::pair<const AuditArtifact*, Move>> moves;
  for (const auto& a : arts) {
    if (a.meta && a.kind != AuditArtifactKind::transform) moves.push_back({&a, move_of(a)});
  }
  std::vector<Move> distinct;
  for (const auto& [a, m] : moves) {
    if (std::find(distinct.begin(), distinct.end(), m) == distinct.end()) distinct.push_back(m);
  }
  if (distinct.empty()) {
    c.status = AuditStatus::fail;
    c.summary = "the map has no tile or vector map with a sidecar to take its transform from";
    return c;
  }
  std::size_t failing = 0, checked = 0;
  double worst_h = 0.0, worst_v = 0.0;
  for (const auto& p : set.points) {
    if (!p.use) continue;
    // Which move: the only one, or the tile's that holds the target.
    const AuditArtifact* tile = moves.front().first;
    Move move = distinct.front();
    if (distinct.size() > 1) {
      tile = nullptr;
      for (const auto& [a, m] : moves) {
        const auto b = bounds_of(*a);
        if (!b || a->meta->crs) continue;
        const auto x = from_ecef(a->meta->coordinates, p.target.m);
        if (x && x->x() >= b->first.x() && x->x() <= b->second.x() && x->y() >= b->first.y() && x->y() <= b->second.y()) {
          tile = a;
          move = m;
          break;
        }
      }
      if (!tile) {
        ++failing;
        c.evidence.push_back(p.id + ": no tile holds it, and the map's tiles were moved differently: which transform is "
                                    "the map's there is unknown");
        continue;
      }
    }
    std::string why;
    const io::TransformFile* t = transforms.find(move, *tile, why);
    if (!move.sha256.empty() && !t) {
      ++failing;
      c.evidence.push_back(p.id + ": not checked: " + name_of(*tile) + ": " + why);
      continue;
    }
    // The control set's frames must be stated, and be the transform's
    // (without one: the map's own frame on both sides).
    if (!set.source_frame || !set.target_frame) {
      throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                  *request.checkpoints + ": the checkpoints state no " + (!set.source_frame ? "source" : "target") +
                      " frame ('# source_frame = NAME@EPOCH' / '# target_frame = …', or '# frame = …' in each file of a "
                      "pair): a checkpoint compared in an unknown frame proves nothing");
    }
    for (const auto* f : {&set.source_frame, &set.target_frame}) {
      geodesy::require_epoch_if_dynamic(**f, *request.checkpoints + ": the checkpoints' frame");
    }
    if (!t && (set.source_frame->to_string() != move.output_frame || set.target_frame->to_string() != move.output_frame)) {
      throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                  *request.checkpoints + ": its frames (" + set.source_frame->to_string() + " -> " + set.target_frame->to_string() +
                      ") are not the map's " + (move.output_frame.empty() ? std::string("(unknown)") : move.output_frame) +
                      ", which no transform file moved");
    }
    if (t) {
      const auto& from = move.inverse ? t->target_frame : t->source_frame;
      const auto& to = move.inverse ? t->source_frame : t->target_frame;
      // The same frame, and the same coordinate epoch where both name one.
      const auto differs = [](const std::optional<geodesy::Frame>& a, const std::optional<geodesy::Frame>& b) {
        if (!a || !b) return false;  // the transform names none: the set's is taken
        if (a->name() != b->name()) return true;
        return a->epoch().has_value() != b->epoch().has_value() || (a->epoch() && a->epoch()->year != b->epoch()->year);
      };
      if (differs(set.source_frame, from) || differs(set.target_frame, to)) {
        throw Error(ErrorKind::input, "E_CHECKPOINT_FRAME",
                    *request.checkpoints + ": its frames (" + (set.source_frame ? set.source_frame->to_string() : "?") + " -> " +
                        (set.target_frame ? set.target_frame->to_string() : "?") + ") are not the map's transform's (" +
                        (from ? from->to_string() : "?") + " -> " + (to ? to->to_string() : "?") + ")");
      }
    }
    const std::optional<geodesy::DecimalYear> epoch = p.epoch ? p.epoch : year(move.epoch);
    Eigen::Vector3d moved = p.source.m;
    std::optional<Eigen::Matrix3d> cov;
    try {
      if (t) {
        moved = t->apply(p.source, epoch, move.inverse, *request.checkpoints + ": " + p.id).m;
        cov = propagated_covariance_m2(*t, p.source, epoch, move.inverse);
      }
    } catch (const Error& e) {
      ++failing;
      c.evidence.push_back(p.id + ": not checked: " + e.what());
      continue;
    }
    ++checked;
    // Surveyed − map (measured minus map), ENU at the mark: the sign of
    // fit's residuals (target − transformed source), one convention
    // everywhere (issue 40 point 11; docs/conventions.md).
    const Eigen::Vector3d d = -enu_difference(p.target.m, moved);
    const double h = std::hypot(d.x(), d.y()), v = std::abs(d.z());
    worst_h = std::max(worst_h, h);
    worst_v = std::max(worst_v, v);
    std::string sigma = "the map's transform carries no uncertainty";
    if (cov && cov->allFinite()) {
      const geodesy::GeodeticPosition g = geodesy::geodetic_from_ecef(geodesy::Ellipsoid::grs80(), p.target);
      const Eigen::Matrix3d r = geodesy::enu_from_ecef_rotation(g.lat, g.lon);
      const Eigen::Matrix3d enu = r * *cov * r.transpose();
      const auto sd = [&](int k) { return mm(std::sqrt(std::max(0.0, enu(k, k)))); };  // a variance rounded below 0 is 0
      sigma = "propagated σ east " + sd(0) + ", north " + sd(1) + ", up " + sd(2);
    }
    const bool bad = !(h <= l.checkpoint_horizontal_m) || !(v <= l.checkpoint_vertical_m);
    if (bad) ++failing;
    c.evidence.push_back(p.id + ": " + (bad ? "FAIL " : "") + "horizontal " + cm(h) + ", vertical " + cm(d.z()) + " (east " +
                         cm(d.x()) + ", north " + cm(d.y()) + "); " + sigma);
  }
  c.status = failing == 0 && checked > 0 ? AuditStatus::pass : AuditStatus::fail;
  c.summary = std::to_string(checked) + " checkpoints of " + *request.checkpoints + ": largest horizontal " + cm(worst_h) +
              ", vertical " + cm(worst_v) + (failing ? "; " + std::to_string(failing) + " fail" : "");
  if (checked == 0 && failing == 0) c.summary = *request.checkpoints + " has no checkpoint in use";
  return c;
}

}  // namespace geoanchor::workflow::audit_detail
