// Which candidate a point takes: PROJ's own choice with geoanchor's rules
// (a datum change must hold the point, a better one whose grid is missing
// is named), fallbacks, and the tests that give a whole batch one choice.

#include "geoanchor/crs/crs_operation.hpp"

#include <algorithm>
#include <cmath>

#include "crs_operation_impl.hpp"

namespace geoanchor::io {

using detail::Candidate;

CrsOperation::Impl::Choice CrsOperation::Impl::choose(double a, double b, double c, double lon, double lat,
                                                      bool lonlat_known) const {
  auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  Choice choice;
  if (available_count == 1) {
    choice.use = 0;
  } else if (available_count > 1) {
    const PJ_COORD native = source_swapped ? proj_coord(b, a, c, t.value_or(0.0)) : proj_coord(a, b, c, t.value_or(0.0));
    const int k = proj_get_suggested_operation(ctx.get(), available.get(), PJ_FWD, native);
    if (k >= 0 && static_cast<std::size_t>(k) < available_count) choice.use = static_cast<std::size_t>(k);
  }
  // One PROJ cannot run, or (where the point's longitude and latitude are
  // known) whose datum change does not hold the point, is no choice.
  if (choice.use && (!all[*choice.use].op || (lonlat_known && !all[*choice.use].holds(lon, lat)))) {
    if (all[*choice.use].op) choice.set_aside = choice.use;
    choice.use.reset();
  }
  if (!lonlat_known) return choice;
  for (std::size_t i = available_count; i < all.size(); ++i) {
    const auto& m = all[i];
    if (!m.holds(lon, lat) || (m.info.area && !m.info.area->contains(lon, lat))) continue;
    if (!choice.use || better(m.info.accuracy_m, all[*choice.use].info.accuracy_m)) {
      choice.missing_better = i;
      break;
    }
  }
  return choice;
}

std::optional<std::size_t> CrsOperation::Impl::fallback(double lon, double lat, const std::vector<std::size_t>& tried) const {
  auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  std::optional<std::size_t> use;
  for (std::size_t i = 0; i < available_count; ++i) {
    if (std::find(tried.begin(), tried.end(), i) != tried.end()) continue;
    if (!all[i].op || !all[i].holds(lon, lat)) continue;
    if (!use || better(all[i].info.accuracy_m, all[*use].info.accuracy_m)) use = i;
  }
  return use;
}

// Whether every point of a batch in a projected source lies inside each of
// `areas` (the CRSs' and the datum change's areas of use), decided from the
// boundary of the batch's bounding box in the source plane: a projection
// maps the box's inside within the curve its boundary maps to, so a
// boundary that maps inside a (convex) longitude/latitude box keeps every
// point inside. The boundary is sampled densely and held a small margin
// inside each area, for the curve between samples; a batch that fails the
// test is checked point by point.
bool CrsOperation::Impl::batch_inside(const std::vector<const CrsArea*>& areas, const std::vector<double>& a,
                                      const std::vector<double>& b) const {
  constexpr int kSamplesPerEdge = 32;
  constexpr double kMargin = 1e-4;  // of the area's span, degrees
  if (a.empty() || !to_lonlat) return false;
  for (const CrsArea* area : areas) {
    if (area->west_deg > area->east_deg) return false;  // across the antimeridian: point by point
  }
  double amin = a[0], amax = a[0], bmin = b[0], bmax = b[0];
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i])) return false;
    amin = std::min(amin, a[i]), amax = std::max(amax, a[i]);
    bmin = std::min(bmin, b[i]), bmax = std::max(bmax, b[i]);
  }
  std::vector<double> x, y;
  for (int k = 0; k <= kSamplesPerEdge; ++k) {
    const double f = static_cast<double>(k) / kSamplesPerEdge;
    const double xa = amin + f * (amax - amin), yb = bmin + f * (bmax - bmin);
    x.insert(x.end(), {xa, xa, amin, amax});
    y.insert(y.end(), {bmin, bmax, yb, yb});
  }
  proj_trans_generic(to_lonlat.get(), PJ_FWD, x.data(), sizeof(double), x.size(), y.data(), sizeof(double), y.size(),
                     nullptr, 0, 0, nullptr, 0, 0);
  for (const CrsArea* area : areas) {
    const double mw = kMargin * (area->east_deg - area->west_deg), mn = kMargin * (area->north_deg - area->south_deg);
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (!(x[i] >= area->west_deg + mw && x[i] <= area->east_deg - mw && y[i] >= area->south_deg + mn &&
            y[i] <= area->north_deg - mn)) {
        return false;
      }
    }
  }
  return true;
}

// The one candidate every point of a box takes, when each available
// candidate's area holds the box whole or not at all, and so does each
// candidate with a missing grid that would be better than the choice;
// nullopt otherwise. PROJ's choice depends only on which
// candidates' areas hold a point (PROJ tests each candidate's area, as a
// box, and ranks those that hold the point), so it is the same for every
// point of such a box.
std::optional<std::size_t> CrsOperation::Impl::uniform_choice(const Box& box, double a0, double b0, double c0, double lon0,
                                                                double lat0) const {
  const auto whole_or_none = [&](const Candidate& c) {
    std::vector<const CrsArea*> areas;
    if (c.info.area) areas.push_back(&*c.info.area);
    for (const auto& d : c.datum_areas) areas.push_back(&d);
    for (const CrsArea* a : areas) {
      if (a->west_deg > a->east_deg) return false;  // across the antimeridian: point by point
      const bool whole = box.west >= a->west_deg && box.east <= a->east_deg && box.south >= a->south_deg && box.north <= a->north_deg;
      const bool none = box.east < a->west_deg || box.west > a->east_deg || box.north < a->south_deg || box.south > a->north_deg;
      if (!whole && !none) return false;
    }
    return true;
  };
  for (std::size_t i = 0; i < available_count; ++i) {
    if (!whole_or_none(all[i])) return std::nullopt;
  }
  const Choice choice = choose(a0, b0, c0, lon0, lat0, true);
  if (choice.missing_better || !choice.use) return std::nullopt;  // the per-point path names the point, or counts the fallback
  // A candidate whose grid is missing matters only where it would be
  // better than the choice (choose() then names it): its area must hold
  // the box whole or not at all only if it is.
  const auto better = [](const std::optional<double>& x, const std::optional<double>& y) { return x && (!y || *x < *y); };
  for (std::size_t i = available_count; i < all.size(); ++i) {
    if (better(all[i].info.accuracy_m, all[*choice.use].info.accuracy_m) && !whole_or_none(all[i])) return std::nullopt;
  }
  return choice.use;
}

std::optional<CrsOperation::Impl::Box> CrsOperation::Impl::box_of(const std::vector<double>& lon, const std::vector<double>& lat) {
  if (lon.empty()) return std::nullopt;
  Box box{lon[0], lat[0], lon[0], lat[0]};
  for (std::size_t i = 0; i < lon.size(); ++i) {
    if (!std::isfinite(lon[i]) || !std::isfinite(lat[i])) return std::nullopt;
    box = {std::min(box.west, lon[i]), std::min(box.south, lat[i]), std::max(box.east, lon[i]), std::max(box.north, lat[i])};
  }
  return box;
}

}  // namespace geoanchor::io
