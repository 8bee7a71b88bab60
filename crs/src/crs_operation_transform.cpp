// CrsOperation run over arrays of points: transform() (the epoch check, points
// that count or not, each point's candidate, batches per candidate, fallbacks)
// and estimate().

#include "geoanchor/crs/crs_operation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "crs_operation_impl.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::io {

using detail::accuracy_text;
using detail::AreaTally;
using detail::Candidate;
using detail::joined;

namespace {

// `op` over n points in place (c may be null: 2-D), at epoch t if given.
void trans_arrays(PJ* op, double* a, double* b, double* c, std::size_t n, const std::optional<double>& t) {
  double t_value = t.value_or(0.0);
  proj_trans_generic(op, PJ_FWD, a, sizeof(double), n, b, sizeof(double), n, c, c ? sizeof(double) : 0, c ? n : 0,
                     t ? &t_value : nullptr, 0, t ? 1 : 0);
}

}  // namespace

// One batch of points that count, as transform_counted runs it: the points
// (a, b, c, moved in place), as given (after `pre`) and in longitude and
// latitude (empty where nothing needs them), and the steps that move them.
struct CrsOperation::Impl::Batch {
  Impl& m;
  double* a;
  double* b;
  double* c;
  std::size_t n;
  const std::function<std::string(std::size_t)>& point_name;
  std::size_t z_stride, z_count;
  double t_value;
  const std::vector<double>& in_a;
  const std::vector<double>& in_b;
  const std::vector<double>& in_c;
  const std::vector<double>& lon;
  const std::vector<double>& lat;

  // A point's coordinates as given, each named by its axis ("Lon=8.5, Lat=47.4, h=480").
  std::string coordinates_of(std::size_t i) const;
  [[noreturn]] void fail_point(std::size_t i, const Candidate& op, const std::string& why) const;
  // A point outside the area of use of every datum change PROJ can run here
  // for the pair (PROJ would apply one anyway): `op` is the best-ranked.
  [[noreturn]] void fail_area(std::size_t i, const Candidate& op) const;
  void run(const Candidate& op, double* x, double* y, double* z, std::size_t count);
  bool finite(std::size_t i) const;
  void note_fallback(std::size_t i, const Candidate& better, bool missing_grid);

  // The one candidate there is.
  void run_single();
  // Each point's operation (PROJ's own choice), then one batch per
  // operation, then the points an operation could not move (outside its
  // grid) one by one.
  void run_chosen(const std::optional<Box>& box);
  // Each point's candidate: `uniform` for all, or each point's own.
  std::vector<std::size_t> choose_each(const std::optional<std::size_t>& uniform);
  // Each run of points with one candidate, in place; then each point it
  // could not move, with the next candidate that holds it (--allow-fallback).
  void run_each(std::vector<std::size_t>& use, const std::optional<std::size_t>& uniform);
};

void CrsOperation::transform(double* a, double* b, double* c, std::size_t n,
                             const std::function<std::string(std::size_t)>& point_name, Count counted) {
  Impl& m = *impl_;
  if (n == 0) return;
  if (!m.epoch_probe.empty() && !m.probing) {
    // The operation at two epochs 40 years apart: the same result (to 1 µm)
    // means it does not depend on the epoch, and none is needed.
    constexpr double kProbeEpochs[2] = {1990.0, 2030.0};
    constexpr double kEpochFree_m = 1e-6;
    const bool angular = m.target_is_lonlat;
    std::vector<double> a2(a, a + n), b2(b, b + n), c2;
    if (c) c2.assign(c, c + n);
    m.probing = true;
    struct Reset {
      Impl& m;
      ~Reset() {
        m.probing = false;
        m.t.reset();
      }
    } reset{m};
    m.t = kProbeEpochs[0];
    transform(a, b, c, n, point_name, counted);
    m.t = kProbeEpochs[1];
    transform(a2.data(), b2.data(), c ? c2.data() : nullptr, n, point_name, Count::no);
    constexpr double kMetresPerDegree = 111319.49;  // for differences of degrees, to 1 %
    for (std::size_t i = 0; i < n; ++i) {
      const double da = (a[i] - a2[i]) * (angular ? kMetresPerDegree : 1.0);
      const double db = (b[i] - b2[i]) * (angular ? kMetresPerDegree : 1.0);
      const double dc = c ? c[i] - c2[i] : 0.0;
      const double d = std::sqrt(da * da + db * db + dc * dc);
      if (!(d <= kEpochFree_m)) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    m.where + ": " + point_name(i) + ": " + m.src_name + " → " + m.dst_name + ": PROJ's operation '" +
                        m.epoch_probe + "' is time-dependent and moves this point by " + format_shortest(d) +
                        " m between epochs 1990.0 and 2030.0, so its result depends on the coordinates' epoch, which "
                        "neither CRS states; give it as CRS@YYYY.Y (on the dynamic CRS; between two static CRSs, on "
                        "either)");
      }
      m.epoch_free_worst_m = std::max(m.epoch_free_worst_m, d);
    }
    m.epoch_probed += n;
    return;
  }
  if (counted == Count::no) {
    // The same, with the tallies (points per candidate, areas, fallbacks) as they were.
    std::vector<std::size_t> points;
    for (const auto& k : m.all) points.push_back(k.info.points);
    const AreaTally source_area = m.source_area, target_area = m.target_area;
    const std::size_t fallbacks = m.fallbacks, set_aside = m.set_aside;
    const std::string first_fallback = m.first_fallback, first_set_aside = m.first_set_aside;
    const std::set<std::string> fallback_reasons = m.fallback_reasons;
    transform(a, b, c, n, point_name, Count::yes);
    m.fallback_reasons = fallback_reasons;
    for (std::size_t k = 0; k < m.all.size(); ++k) m.all[k].info.points = points[k];
    m.source_area = source_area;
    m.target_area = target_area;
    m.fallbacks = fallbacks;
    m.set_aside = set_aside;
    m.first_fallback = first_fallback;
    m.first_set_aside = first_set_aside;
    return;
  }
  m.transform_counted(a, b, c, n, point_name);
}

void CrsOperation::Impl::transform_counted(double* a, double* b, double* c, std::size_t n,
                                           const std::function<std::string(std::size_t)>& point_name) {
  const std::size_t z_stride = c ? sizeof(double) : 0;
  const std::size_t z_count = c ? n : 0;
  double t_value = t.value_or(0.0);
  // Geocentric x, y, z to longitude, latitude, height on their datum (a
  // conversion), which the candidates start from. The points' own
  // coordinates name them in errors below as converted.
  if (pre) trans_arrays(pre.get(), a, b, c, n, std::nullopt);
  const std::vector<double> in_a(a, a + n), in_b(b, b + n);
  std::vector<double> in_c;
  if (c) in_c.assign(c, c + n);

  // Longitude and latitude of each point where choices or areas need them
  // (a geocentric source's with its z: x and y alone would be at 0°).
  const bool single = available_count == 1 && all.size() == 1;
  std::vector<double> lon_store, lat_store;
  bool tallied = false;  // the points counted against the CRSs' areas of use
  std::vector<const CrsArea*> areas;  // those a single candidate's batch is held to
  if (single) {
    if (source_area.area) areas.push_back(&*source_area.area);
    if (target_area.area) areas.push_back(&*target_area.area);
    for (const auto& d : all.front().datum_areas) areas.push_back(&d);
  }
  if (source_is_lonlat) {
    // The input itself (no copy).
  } else if (to_lonlat && single && source_is_planar && batch_inside(areas, in_a, in_b)) {
    source_area.seen += n;  // the whole batch lies inside: no point needs its own inverse
    target_area.seen += n;
    tallied = true;
  } else if (to_lonlat) {
    lon_store = in_a;
    lat_store = in_b;
    std::vector<double> z = c ? in_c : std::vector<double>();
    proj_trans_generic(to_lonlat.get(), PJ_FWD, lon_store.data(), sizeof(double), n, lat_store.data(), sizeof(double), n,
                       c ? z.data() : nullptr, c ? sizeof(double) : 0, c ? n : 0, nullptr, 0, 0);
  }
  const std::vector<double>& lon = source_is_lonlat ? in_a : lon_store;
  const std::vector<double>& lat = source_is_lonlat ? in_b : lat_store;
  const std::optional<Impl::Box> box = Impl::box_of(lon, lat);  // of the longitudes and latitudes
  if (!lon.empty()) {
    // A batch whose box both areas hold is counted whole; otherwise point by point.
    const auto holds_box = [&](const AreaTally& tally) {
      const auto& r = tally.area;
      return !r || (box && r->west_deg <= r->east_deg && box->west >= r->west_deg && box->east <= r->east_deg &&
                    box->south >= r->south_deg && box->north <= r->north_deg);
    };
    if (holds_box(source_area) && holds_box(target_area)) {
      source_area.seen += n;
      target_area.seen += n;
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        source_area.check(lon[i], lat[i], [&] { return point_name(i); });
        target_area.check(lon[i], lat[i], [&] { return point_name(i); });
      }
    }
    tallied = true;
  }

  Batch batch{*this, a, b, c, n, point_name, z_stride, z_count, t_value, in_a, in_b, in_c, lon, lat};
  if (single) {
    batch.run_single();
  } else {
    batch.run_chosen(box);
  }
  if (target_is_lonlat && !tallied) {
    for (std::size_t i = 0; i < n; ++i) {
      source_area.check(a[i], b[i], [&] { return point_name(i); });
      target_area.check(a[i], b[i], [&] { return point_name(i); });
    }
  }
}

std::string CrsOperation::Impl::Batch::coordinates_of(std::size_t i) const {
  auto label = [&](std::size_t k) { return k < m.axis_labels.size() ? m.axis_labels[k] + "=" : std::string(); };
  std::string coords = label(0) + format_shortest(in_a[i]) + ", " + label(1) + format_shortest(in_b[i]);
  if (c) coords += ", " + label(2) + format_shortest(in_c[i]);
  return coords;
}

void CrsOperation::Impl::Batch::fail_point(std::size_t i, const Candidate& op, const std::string& why) const {
  const std::string coords = coordinates_of(i);
  std::vector<std::string> grids;
  for (const auto& g : op.info.grids) grids.push_back(g.name);
  throw Error(ErrorKind::input, "E_CRS_TRANSFORM",
              m.where + ": " + point_name(i) + ": (" + coords + ") in " + m.src_name + ": " + why + " '" +
                  op.info.name + "'" + (grids.empty() ? "" : " (grid " + joined(grids) + ")") + " to " + m.dst_name +
                  (grids.empty() ? "" : "; the point is outside the grid's extent") +
                  (m.options.allow_fallback ? "" : "; no other operation is used for it without --allow-fallback"));
}

void CrsOperation::Impl::Batch::fail_area(std::size_t i, const Candidate& op) const {
  const CrsArea* out = nullptr;
  for (const auto& d : op.datum_areas) {
    if (!d.contains(lon[i], lat[i])) out = &d;
  }
  std::vector<std::string> grids;
  for (const auto& g : op.info.grids) grids.push_back(g.name);
  // One whose grid is not here may hold it.
  std::string missing;
  for (std::size_t k = m.available_count; k < m.all.size() && missing.empty(); ++k) {
    if (!m.all[k].holds(lon[i], lat[i])) continue;
    std::vector<std::string> absent;
    for (const auto& g : m.all[k].info.grids) {
      if (!g.available) absent.push_back(g.name);
    }
    missing = "; PROJ's operation '" + m.all[k].info.name + "' holds it but needs the grid " + joined(absent) +
              ", which is not on this machine (PROJ looked in " + joined(detail::proj_search_paths()) + ")";
  }
  throw Error(ErrorKind::input, "E_CRS_TRANSFORM",
              m.where + ": " + point_name(i) + ": (" + coordinates_of(i) + ") in " + m.src_name + ", at latitude " +
                  format_shortest(lat[i]) + "°, longitude " + format_shortest(lon[i]) +
                  "°, lies outside the area of use of " +
                  (m.available_count == 1 ? "PROJ's only operation '" : "every operation PROJ can run here, the best-ranked '") +
                  op.info.name + "' (" + accuracy_text(op.info.accuracy_m) + (grids.empty() ? "" : ", grid " + joined(grids)) +
                  ") to " + m.dst_name +
                  (out ? ": " + out->name + ", latitude " + format_shortest(out->south_deg) + "° to " +
                             format_shortest(out->north_deg) + "°, longitude " + format_shortest(out->west_deg) + "° to " +
                             format_shortest(out->east_deg) + "°"
                       : std::string()) +
                  "; a datum change's parameters hold in its own area only" +
                  (missing.empty() ? ", and PROJ knows no other operation for this point but a ballpark one" : missing));
}

void CrsOperation::Impl::Batch::run(const Candidate& op, double* x, double* y, double* z, std::size_t count) {
  proj_trans_generic(op.op.get(), PJ_FWD, x, sizeof(double), count, y, sizeof(double), count, z, z ? sizeof(double) : 0,
                     z ? count : 0, m.t ? &t_value : nullptr, 0, m.t ? 1 : 0);
}

bool CrsOperation::Impl::Batch::finite(std::size_t i) const {
  return std::isfinite(a[i]) && std::isfinite(b[i]) && (!c || std::isfinite(c[i]));
}

void CrsOperation::Impl::Batch::note_fallback(std::size_t i, const Candidate& better, bool missing_grid) {
  if (m.fallbacks++ == 0) m.first_fallback = point_name(i);
  if (!missing_grid) {
    m.fallback_reasons.insert("'" + better.info.name + "' cannot move them (outside its grid)");
    return;
  }
  std::vector<std::string> grids;
  for (const auto& g : better.info.grids) {
    if (!g.available) grids.push_back(g.name);
  }
  m.fallback_reasons.insert("'" + better.info.name + "' (" + accuracy_text(better.info.accuracy_m) + ") needs " + joined(grids) +
                            ", not on this machine");
}

void CrsOperation::Impl::Batch::run_single() {
  Candidate& op = m.all.front();
  if (!lon.empty() && !op.datum_areas.empty()) {
    for (std::size_t i = 0; i < n; ++i) {
      if (!op.holds(lon[i], lat[i])) fail_area(i, op);
    }
  }
  proj_trans_generic(op.op.get(), PJ_FWD, a, sizeof(double), n, b, sizeof(double), n, c, z_stride, z_count,
                     m.t ? &t_value : nullptr, 0, m.t ? 1 : 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite(i)) fail_point(i, op, "PROJ cannot move it with");
  }
  op.info.points += n;
}

void CrsOperation::Impl::Batch::run_chosen(const std::optional<Box>& box) {
  // A batch whose longitude/latitude box every candidate's area holds
  // whole or misses whole has one choice for all its points. Only for a
  // source in longitude and latitude: PROJ tests a projected source's
  // point against the box of each area's image in the plane, which holds
  // points outside the area too.
  const std::optional<std::size_t> uniform = m.source_is_lonlat && box
                                                 ? m.uniform_choice(*box, in_a[0], in_b[0], c ? in_c[0] : 0.0, lon[0], lat[0])
                                                 : std::nullopt;
  std::vector<std::size_t> use = choose_each(uniform);
  run_each(use, uniform);
}

std::vector<std::size_t> CrsOperation::Impl::Batch::choose_each(const std::optional<std::size_t>& uniform) {
  std::vector<std::size_t> use(n);
  if (uniform) std::fill(use.begin(), use.end(), *uniform);
  // Otherwise each point's, once per signature (the areas that hold it).
  if (m.areas_chosen_by.empty()) {
    for (const auto& k : m.all) {
      if (k.info.area) m.areas_chosen_by.push_back(&*k.info.area);
      for (const auto& d : k.datum_areas) m.areas_chosen_by.push_back(&d);
    }
  }
  const bool by_signature = m.source_is_lonlat;
  Impl::Signature bits;
  for (std::size_t i = 0; i < n && !uniform; ++i) {
    const double plon = lon.empty() ? 0.0 : lon[i], plat = lat.empty() ? 0.0 : lat[i];
    Impl::Choice choice;
    // (Only in the ranges where CrsArea::contains and PROJ's boxes agree.)
    if (by_signature && plon >= -180.0 && plon <= 180.0 && plat >= -90.0 && plat <= 90.0) {
      m.signature(plon, plat, bits);
      const auto known = std::find_if(m.choices_by_signature.begin(), m.choices_by_signature.end(),
                                      [&](const auto& e) { return e.first == bits; });
      if (known != m.choices_by_signature.end()) {
        choice = known->second;
      } else {
        choice = m.choose(in_a[i], in_b[i], c ? in_c[i] : 0.0, plon, plat, true);
        m.choices_by_signature.emplace_back(bits, choice);
      }
    } else {
      choice = m.choose(in_a[i], in_b[i], c ? in_c[i] : 0.0, plon, plat, !lon.empty());
    }
    if (choice.missing_better && !m.options.allow_fallback) {
      const auto& op = m.all[*choice.missing_better];
      std::vector<std::string> grids;
      for (const auto& g : op.info.grids) {
        if (!g.available) grids.push_back(g.name);
      }
      throw Error(ErrorKind::input, "E_CRS_GRID_MISSING",
                  m.where + ": " + point_name(i) + ": " + m.src_name + " → " + m.dst_name + ": PROJ's operation '" +
                      op.info.name + "' (" + accuracy_text(op.info.accuracy_m) + ") for this point needs the grid " +
                      joined(grids) + ", which is not on this machine; PROJ looked in " +
                      joined(detail::proj_search_paths()) +
                      " (network access off); --allow-fallback uses the next operation instead");
    }
    if (choice.missing_better) note_fallback(i, m.all[*choice.missing_better], true);  // --allow-fallback: a worse operation
    if (!choice.use) choice.use = lon.empty() ? std::nullopt : m.fallback(plon, plat, {});
    if (!choice.use && lon.empty()) fail_point(i, m.all.front(), "no operation's area of use is known to hold it; the best-ranked is");
    if (!choice.use) fail_area(i, m.all[choice.set_aside.value_or(0)]);
    if (choice.set_aside && m.set_aside++ == 0) {
      m.first_set_aside = point_name(i) + " ('" + m.all[*choice.set_aside].info.name + "' set aside for '" +
                          m.all[*choice.use].info.name + "')";
    }
    use[i] = *choice.use;
  }
  return use;
}

void CrsOperation::Impl::Batch::run_each(std::vector<std::size_t>& use, const std::optional<std::size_t>& uniform) {
  if (uniform) run(m.all[*uniform], a, b, c, n);  // in place: a, b, c still hold the input
  // Otherwise each run of consecutive points with one operation, in place.
  for (std::size_t i = 0; i < n && !uniform;) {
    std::size_t j = i + 1;
    while (j < n && use[j] == use[i]) ++j;
    run(m.all[use[i]], a + i, b + i, c ? c + i : nullptr, j - i);
    i = j;
  }
  std::vector<std::size_t> tried;
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t k = use[i];
    tried.assign(1, k);
    while (!finite(i)) {
      if (!m.options.allow_fallback) fail_point(i, m.all[k], "PROJ cannot move it with");
      if (lon.empty()) fail_point(i, m.all[k], "PROJ cannot move it with");
      note_fallback(i, m.all[k], false);
      const auto next = m.fallback(lon[i], lat[i], tried);
      if (!next) fail_point(i, m.all[k], "PROJ cannot move it with");
      k = *next;
      tried.push_back(k);
      a[i] = in_a[i];
      b[i] = in_b[i];
      if (c) c[i] = in_c[i];
      run(m.all[k], a + i, b + i, c ? c + i : nullptr, 1);
    }
    use[i] = k;
    m.all[k].info.points += 1;
  }
}

void CrsOperation::estimate(double* a, double* b, double* c, std::size_t n) const {
  const Impl& m = *impl_;
  if (n == 0 || m.all.empty()) return;
  if (m.pre) trans_arrays(m.pre.get(), a, b, c, n, std::nullopt);
  // PROJ's best-ranked available operation it can run; a point it cannot
  // move is NaN.
  const auto first = std::find_if(m.all.begin(), m.all.end(), [](const Candidate& k) { return k.op != nullptr; });
  trans_arrays(first->op.get(), a, b, c, n, m.t);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(a[i]) && std::isfinite(b[i]) && (!c || std::isfinite(c[i])))) {
      a[i] = b[i] = std::numeric_limits<double>::quiet_NaN();
      if (c) c[i] = std::numeric_limits<double>::quiet_NaN();
    }
  }
}

}  // namespace geoanchor::io
