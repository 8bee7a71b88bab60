// CrsOperation's construction: PROJ's candidate operations for a pair of
// CRSs, and the checks that take them or refuse the pair (epochs, ensembles,
// grids not on the machine).

#include "geoanchor/crs/crs_operation.hpp"

#include <algorithm>
#include <cctype>

#include <proj_experimental.h>

#include "crs_impl.hpp"
#include "crs_operation_impl.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/base/hash.hpp"

namespace geoanchor::io {

using detail::accuracy_text;
using detail::Candidate;
using detail::joined;
using detail::list_operations;
using detail::Pj;
using detail::text_or;

namespace detail {

std::string joined(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::string accuracy_text(const std::optional<double>& a) {
  return a ? "±" + format_shortest(*a) + " m" : std::string("accuracy not stated");
}

}  // namespace detail

namespace {

// Whether an operation (or a step of a concatenated one) is evaluated at an
// epoch: EPSG's time-dependent Helmert methods and point-motion (velocity
// grid) methods.
bool is_time_dependent(PJ_CONTEXT* ctx, PJ* op) {
  const int steps = proj_concatoperation_get_step_count(ctx, op);
  if (steps > 0) {
    for (int i = 0; i < steps; ++i) {
      Pj step(proj_concatoperation_get_step(ctx, op, i));
      if (step && is_time_dependent(ctx, step.get())) return true;
    }
    return false;
  }
  const char* method = nullptr;
  if (!proj_coordoperation_get_method_info(ctx, op, &method, nullptr, nullptr) || !method) return false;
  std::string m(method);
  for (char& c : m) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return m.find("time-dependent") != std::string::npos || m.find("point motion") != std::string::npos ||
         m.find("velocity") != std::string::npos;
}

// The areas of use of an operation's datum-changing steps (see Candidate).
void datum_change_areas(PJ_CONTEXT* ctx, PJ* op, std::vector<CrsArea>& out) {
  const PJ_TYPE type = proj_get_type(op);
  if (type == PJ_TYPE_CONCATENATED_OPERATION) {
    const int steps = proj_concatoperation_get_step_count(ctx, op);
    for (int i = 0; i < steps; ++i) {
      Pj step(proj_concatoperation_get_step(ctx, op, i));
      if (step) datum_change_areas(ctx, step.get(), out);
    }
    return;
  }
  if (type == PJ_TYPE_CONVERSION) return;
  double west = 0, south = 0, east = 0, north = 0;
  const char* name = nullptr;
  if (proj_get_area_of_use(ctx, op, &west, &south, &east, &north, &name) && west > -1000.0) {
    out.push_back(CrsArea{text_or(name), west, south, east, north});
  }
}

}  // namespace

namespace detail {

// PROJ's candidate operations for the pair. With `grids` =
// PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID they are exactly
// those proj_create_crs_to_crs chooses among (network access off), and
// `keep` receives PROJ's list for proj_get_suggested_operation; with
// PROJ_GRID_AVAILABILITY_IGNORED they include the operations whose grids
// are not on the machine.
std::vector<Candidate> list_operations(PJ_CONTEXT* ctx, PJ* src, PJ* dst, bool allow_ballpark,
                                       PROJ_GRID_AVAILABILITY_USE grid_use, PjList* keep) {
  PJ_OPERATION_FACTORY_CONTEXT* fc = proj_create_operation_factory_context(ctx, nullptr);
  proj_operation_factory_context_set_allow_ballpark_transformations(ctx, fc, allow_ballpark ? 1 : 0);
  proj_operation_factory_context_set_spatial_criterion(ctx, fc, PROJ_SPATIAL_CRITERION_PARTIAL_INTERSECTION);
  proj_operation_factory_context_set_grid_availability_use(ctx, fc, grid_use);
  PJ_OBJ_LIST* list = proj_create_operations(ctx, src, dst, fc);
  proj_operation_factory_context_destroy(fc);
  std::vector<Candidate> out;
  const int n = list ? proj_list_get_count(list) : 0;
  for (int i = 0; i < n; ++i) {
    Pj raw(proj_list_get(ctx, list, i));
    if (!raw) continue;
    if (!allow_ballpark && proj_coordoperation_has_ballpark_transformation(ctx, raw.get())) {
      if (keep) return {};  // a ballpark one in the list PROJ chooses from: not a list geoanchor uses
      continue;
    }
    Candidate c;
    c.info.name = text_or(proj_get_name(raw.get()));
    const char* auth = proj_get_id_auth_name(raw.get(), 0);
    const char* code = proj_get_id_code(raw.get(), 0);
    if (auth && code) c.info.identifier = std::string(auth) + ":" + code;
    const double accuracy = proj_coordoperation_get_accuracy(ctx, raw.get());
    if (accuracy >= 0.0) c.info.accuracy_m = accuracy;
    if (proj_get_type(raw.get()) == PJ_TYPE_CONVERSION) c.info.accuracy_m = 0.0;  // exact by definition
    const int grids = proj_coordoperation_get_grid_used_count(ctx, raw.get());
    for (int g = 0; g < grids; ++g) {
      const char* short_name = nullptr;
      const char* full_name = nullptr;
      int available = 0;
      if (!proj_coordoperation_get_grid_used(ctx, raw.get(), g, &short_name, &full_name, nullptr, nullptr, nullptr,
                                             nullptr, &available)) {
        continue;
      }
      CrsGridFile f;
      f.name = text_or(short_name);
      f.path = text_or(full_name);
      f.available = available != 0 && !f.path.empty();
      c.info.grids.push_back(std::move(f));
    }
    c.instantiable = proj_coordoperation_is_instantiable(ctx, raw.get()) != 0;
    const bool grids_here =
        std::all_of(c.info.grids.begin(), c.info.grids.end(), [](const CrsGridFile& g) { return g.available; });
    if (!c.instantiable && grids_here) {
      // Its grids are here, yet PROJ cannot run it (a method PROJ does not
      // implement): PROJ says why when asked for its pipeline.
      (void)detail::take_last_proj_error();
      (void)proj_as_proj_string(ctx, raw.get(), PJ_PROJ_5, nullptr);
      c.unusable = detail::take_last_proj_error();
      if (c.unusable.empty()) c.unusable = "PROJ cannot instantiate it";
    }
    c.instantiable = c.instantiable && grids_here;
    datum_change_areas(ctx, raw.get(), c.datum_areas);
    double west = 0, south = 0, east = 0, north = 0;
    const char* area = nullptr;
    if (proj_get_area_of_use(ctx, raw.get(), &west, &south, &east, &north, &area) && west > -1000.0) {
      c.info.area = CrsArea{text_or(area), west, south, east, north};
    }
    c.info.time_dependent = is_time_dependent(ctx, raw.get());
    if (const char* ps = proj_as_proj_string(ctx, raw.get(), PJ_PROJ_5, nullptr)) {
      const std::string text(ps);  // methods PROJ writes as PROJ strings: deformation models, epoch-dependent sets
      c.info.time_dependent = c.info.time_dependent || text.find("t_epoch") != std::string::npos ||
                              text.find("proj=deformation") != std::string::npos ||
                              text.find("proj=defmodel") != std::string::npos;
    }
    if (c.instantiable) {
      (void)detail::take_last_proj_error();
      c.op.reset(proj_normalize_for_visualization(ctx, raw.get()));
      if (!c.op) {
        c.instantiable = false;
        c.unusable = detail::take_last_proj_error();
        if (c.unusable.empty()) c.unusable = "PROJ cannot give it in longitude/easting-first order";
      }
    }
    if (c.op) {
      const char* proj_text = proj_as_proj_string(ctx, c.op.get(), PJ_PROJ_5, nullptr);
      c.info.proj_string = text_or(proj_text);
    }
    out.push_back(std::move(c));
  }
  if (keep) {
    keep->reset(list);
  } else {
    proj_list_destroy(list);
  }
  return out;
}

}  // namespace detail

namespace {

bool is_geographic_degrees(const CrsDescription& d) {
  if (d.horizontal_type != "geographic 2D" && d.horizontal_type != "geographic 3D") return false;
  if (d.prime_meridian_deg != 0.0 || d.axes.size() < 2) return false;
  return detail::same_unit_factor(d.axes[0].unit_to_si, detail::kRadiansPerDegree);
}

// The geographic 3D CRS (latitude, longitude, ellipsoidal height; degrees,
// metres) on a geocentric CRS's datum.
Pj geographic_3d_on_datum(PJ_CONTEXT* ctx, PJ* geocentric) {
  Pj datum(proj_crs_get_datum(ctx, geocentric));
  if (!datum) datum.reset(proj_crs_get_datum_ensemble(ctx, geocentric));
  if (!datum) return nullptr;
  Pj cs(proj_create_ellipsoidal_3D_cs(ctx, PJ_ELLPS3D_LATITUDE_LONGITUDE_HEIGHT, "degree", detail::kRadiansPerDegree, "metre", 1.0));
  const std::string name = text_or(proj_get_name(geocentric)) + " (geographic 3D)";
  return Pj(cs ? proj_create_geographic_crs_from_datum(ctx, name.c_str(), datum.get(), cs.get()) : nullptr);
}

}  // namespace

CrsOperation::CrsOperation(const Crs& source, const Crs& target, std::string_view where, Options options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.ctx = detail::quiet_context();
  m.options = options;
  m.where = std::string(where);
  PJ_CONTEXT* ctx = m.ctx.get();
  m.src.reset(proj_create(ctx, source.projjson().c_str()));
  m.dst.reset(proj_create(ctx, target.projjson().c_str()));
  m.src_name = source.display_name();
  m.dst_name = target.display_name();
  const std::string pair = m.src_name + " → " + m.dst_name;
  if (!m.src || !m.dst) throw Error(ErrorKind::io, "E_CRS", m.where + ": " + pair + ": PROJ cannot rebuild a CRS");
  const CrsDescription& sd = source.description();
  const CrsDescription& td = target.description();

  // The horizontal datum changes unless both sides are on the same one (a
  // conversion, or a change of heights only).
  const bool same_datum =
      sd.datum == td.datum && sd.ellipsoid.a_m == td.ellipsoid.a_m && sd.ellipsoid.rf == td.ellipsoid.rf;
  m.settle_epoch(source, target, same_datum, pair);
  const CrsDescription chosen_from = m.list_candidates(sd, td, same_datum, pair);
  m.refuse_unusable(pair);
  m.check_ensembles(sd, td, same_datum, pair);
  m.refuse_missing_grids(pair);
  m.check_time_dependence(source, target, pair);
  m.hash_grids();
  m.prepare_lonlat(chosen_from, sd, td, pair);
}

CrsOperation::~CrsOperation() = default;

void CrsOperation::Impl::settle_epoch(const Crs& source, const Crs& target, bool same_datum, const std::string& pair) {
  const CrsDescription& sd = source.description();
  const CrsDescription& td = target.description();
  // The epoch PROJ evaluates a time-dependent operation at: the dynamic
  // side's coordinate epoch (for a static → dynamic change, the target
  // epoch, as EPSG and the agencies publish it).
  const bool src_dynamic = sd.dynamic, dst_dynamic = td.dynamic;
  if (src_dynamic && dst_dynamic && source.epoch() && target.epoch() && source.epoch()->year != target.epoch()->year) {
    throw Error(ErrorKind::input, "E_CRS_EPOCH",
                where + ": " + pair + ": two coordinate epochs; PROJ moves coordinates between frames at one epoch, "
                "not in time (geoanchor transform moves them with velocities or a plate motion model)");
  }
  // The dynamic side's epoch; between two static CRSs (ETRF2000 -> ETRF2014
  // is time-dependent) the one given on either. A static CRS's epoch that
  // contradicts the dynamic side's is refused: the operation has one.
  for (const auto* c : {&source, &target}) {
    if (c->description().dynamic && c->epoch()) t = c->epoch()->year;
  }
  const bool a_dynamic_side = src_dynamic || dst_dynamic;
  for (const auto* c : {&source, &target}) {
    if (c->description().dynamic || !c->epoch()) continue;
    if (t && *t != c->epoch()->year) {
      throw Error(ErrorKind::input, "E_CRS_EPOCH",
                  where + ": " + pair + ": " + c->display_name() + " is on a static datum and names epoch " +
                      geodesy::format_decimal_year(*c->epoch()) + ", the " +
                      (a_dynamic_side ? "dynamic side " : "other static side ") +
                      geodesy::format_decimal_year(geodesy::DecimalYear{*t}) +
                      "; PROJ evaluates the operation at one epoch and does not move points in time (geoanchor "
                      "transform moves them with velocities): give one epoch");
    }
    t = c->epoch()->year;
  }
  if (!same_datum) {
    for (const auto* c : {&source, &target}) {
      if (c->description().dynamic && !c->epoch() && !t) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    where + ": " + pair + ": " + c->display_name() + " is on a dynamic datum (" +
                        c->description().datum + "): its coordinates change with time, so this datum change needs "
                        "their epoch; give it as CRS@YYYY.Y, e.g. " +
                        (c->text().size() <= 40 && c->text().find('[') == std::string::npos
                             ? c->text()
                             : c->description().identifier.empty() ? std::string("CRS") : c->description().identifier) +
                        "@2024.5");
      }
    }
  }
}

// The candidates (PROJ's, then those whose grids are missing); returns the
// source they start from (a geocentric source's geographic 3D form).
CrsDescription CrsOperation::Impl::list_candidates(const CrsDescription& sd, const CrsDescription& td, bool same_datum,
                                                   const std::string& pair) {
  PJ_CONTEXT* const proj_ctx = ctx.get();
  // The same datum on two prime meridians (Crs::geocentric's ECEF through
  // Greenwich of NTF (Paris)): PROJ calls the change of meridian between
  // them a ballpark, and it is exact.
  const bool meridian_only = same_datum && sd.prime_meridian_deg != td.prime_meridian_deg;
  all = list_operations(proj_ctx, src.get(), dst.get(), meridian_only,
                        PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID, &available);
  CrsDescription chosen_from = sd;  // the source the candidates start from
  if (sd.type == "geocentric" && all.size() > 1) {
    Pj geographic = geographic_3d_on_datum(proj_ctx, src.get());
    Pj raw(geographic ? proj_create_crs_to_crs_from_pj(proj_ctx, src.get(), geographic.get(), nullptr, nullptr) : nullptr);
    if (!raw) throw Error(ErrorKind::io, "E_CRS", where + ": " + pair + ": PROJ cannot give the geocentric source's latitude");
    pre.reset(proj_normalize_for_visualization(proj_ctx, raw.get()));
    src = std::move(geographic);
    all = list_operations(proj_ctx, src.get(), dst.get(), meridian_only,
                          PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID, &available);
    chosen_from.type = chosen_from.horizontal_type = "geographic 3D";
    chosen_from.axes = {CrsAxis{"Geodetic latitude", "Lat", "north", "degree", detail::kRadiansPerDegree, "angular", std::nullopt},
                        CrsAxis{"Geodetic longitude", "Lon", "east", "degree", detail::kRadiansPerDegree, "angular", std::nullopt},
                        CrsAxis{"Ellipsoidal height", "h", "up", "metre", 1.0, "linear", std::nullopt}};
    chosen_from.visualization_axes = {chosen_from.axes[1], chosen_from.axes[0], chosen_from.axes[2]};
    chosen_from.prime_meridian_deg = 0.0;
  }
  available_count = all.size();
  for (auto& c : list_operations(proj_ctx, src.get(), dst.get(), false, PROJ_GRID_AVAILABILITY_IGNORED)) {
    const bool listed = std::any_of(all.begin(), all.end(), [&](const Candidate& a) { return a.info.name == c.info.name; });
    if (!listed && !c.instantiable) all.push_back(std::move(c));
  }
  return chosen_from;
}

void CrsOperation::Impl::refuse_unusable(const std::string& pair) const {
  PJ_CONTEXT* const proj_ctx = ctx.get();
  if (all.empty()) {
    const bool ballpark = !list_operations(proj_ctx, src.get(), dst.get(), true, PROJ_GRID_AVAILABILITY_IGNORED).empty();
    throw Error(ErrorKind::input, "E_CRS_NO_OPERATION",
                where + ": " + pair + ": " +
                    (ballpark ? "PROJ knows only a ballpark operation between them (a datum change of unknown "
                                "accuracy, often metres to hundreds of metres); geoanchor does not use it"
                              : "PROJ knows no operation between them"));
  }
  if (available_count > 0 &&
      std::none_of(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(available_count),
                   [](const Candidate& c) { return c.op != nullptr; })) {
    std::vector<std::string> why;
    for (std::size_t i = 0; i < available_count; ++i) why.push_back("'" + all[i].info.name + "': " + all[i].unusable);
    throw Error(ErrorKind::input, "E_CRS_NO_OPERATION",
                where + ": " + pair + ": PROJ cannot run its operation" + (why.size() > 1 ? "s" : "") +
                    " between them (" + joined(why, "; ") + "); geoanchor uses no other");
  }
}

void CrsOperation::Impl::check_ensembles(const CrsDescription& sd, const CrsDescription& td, bool same_datum,
                                         const std::string& pair) {
  // An ensemble: its members differ by up to its accuracy. A conversion
  // keeps the datum, and an operation no better than that accuracy cannot
  // tell the members apart: both are warned. A finer datum change would
  // depend on the member the coordinates are in: refused.
  std::optional<double> finest;
  for (const auto& c : all) {
    if (c.instantiable && c.info.accuracy_m && (!finest || *c.info.accuracy_m < *finest)) finest = c.info.accuracy_m;
  }
  for (const auto* d : {&sd, &td}) {
    if (!d->ensemble) continue;
    const std::string name = d == &sd ? src_name : dst_name;
    const std::string accuracy = d->ensemble_accuracy_m ? format_shortest(*d->ensemble_accuracy_m) + " m" : "not stated";
    if (same_datum) {
      if (d == &td && sd.ensemble) continue;  // the same ensemble on both sides: said once
      notes.push_back(name + " is on the datum ensemble '" + d->datum + "' (accuracy " + accuracy + "): " + pair +
                      " keeps the datum, so the realization does not change it; the coordinates stay in whichever "
                      "realization they were");
    } else if (finest && d->ensemble_accuracy_m && *finest >= *d->ensemble_accuracy_m) {
      notes.push_back(name + " is on the datum ensemble '" + d->datum + "' (accuracy " + accuracy +
                      "); PROJ's operations between " + src_name + " and " + dst_name + " are no better than ±" +
                      format_shortest(*finest) + " m, so which member the coordinates are in cannot matter at "
                      "that accuracy");
    } else {
      throw Error(ErrorKind::input, "E_CRS_ENSEMBLE",
                  where + ": " + pair + ": " + name + " is on the datum ensemble '" + d->datum + "' (accuracy " +
                      accuracy + "), and this datum change (PROJ's best operation: " +
                      (finest ? "±" + format_shortest(*finest) + " m" : std::string("accuracy not stated")) +
                      ") depends on which member the coordinates are in; give the CRS of one of its members: " +
                      joined(d->ensemble_members));
    }
  }
}

void CrsOperation::Impl::refuse_missing_grids(const std::string& pair) const {
  if (available_count == 0) {
    // Every operation needs a grid that is not here: name them all.
    std::vector<std::string> missing, operations;
    for (const auto& c : all) {
      operations.push_back("'" + c.info.name + "' (" + accuracy_text(c.info.accuracy_m) + ")");
      for (const auto& g : c.info.grids) {
        if (!g.available && std::find(missing.begin(), missing.end(), g.name) == missing.end()) missing.push_back(g.name);
      }
    }
    throw Error(ErrorKind::input, "E_CRS_GRID_MISSING",
                where + ": " + pair + ": PROJ's operations " + joined(operations, "; ") + " need the grids " +
                    joined(missing) + ", none of which is on this machine; PROJ looked in " +
                    joined(detail::proj_search_paths()) + " (network access off); no other operation is known but a "
                    "ballpark one");
  }
}

void CrsOperation::Impl::check_time_dependence(const Crs& source, const Crs& target, const std::string& pair) {
  bool any_time_dependent = false;
  for (std::size_t i = 0; i < available_count; ++i) {
    const auto& c = all[i];
    any_time_dependent = any_time_dependent || c.info.time_dependent;
    // Between two static CRSs a time-dependent route may give the same
    // result at any epoch (MGA94 -> MGA2020 through ITRF2014: the plate
    // motions cancel); that is checked on the points themselves.
    if (c.info.time_dependent && !t && epoch_probe.empty()) epoch_probe = c.info.name;
  }
  for (const auto* c : {&source, &target}) {
    if (!c->description().dynamic && c->epoch() && !any_time_dependent) {
      throw Error(ErrorKind::input, "E_CRS_EPOCH",
                  where + ": " + pair + ": " + c->display_name() + " is on a static datum (" + c->description().datum +
                      ") and no operation PROJ uses between them depends on time: the epoch @" +
                      geodesy::format_decimal_year(*c->epoch()) + " would not be used; give the CRS without it");
    }
  }
}

void CrsOperation::Impl::hash_grids() {
  // Grids in use: hashed once, as they are on this machine.
  for (auto& c : all) {
    for (auto& g : c.info.grids) {
      if (g.available) g.sha256 = options.grid_hashes ? options.grid_hashes->sha256_hex(g.path) : sha256_file_hex(g.path);
    }
  }
}

// The source's axes, and its longitude and latitude where choices or areas need them.
void CrsOperation::Impl::prepare_lonlat(const CrsDescription& chosen_from, const CrsDescription& sd,
                                        const CrsDescription& td, const std::string& pair) {
  PJ_CONTEXT* const proj_ctx = ctx.get();
  source_swapped = chosen_from.axes.size() >= 2 && chosen_from.visualization_axes.size() >= 2 &&
                   chosen_from.axes[0].name != chosen_from.visualization_axes[0].name;
  source_is_lonlat = is_geographic_degrees(chosen_from);
  source_is_planar = chosen_from.horizontal_type == "projected";
  for (const auto& axis : chosen_from.visualization_axes) {
    axis_labels.push_back(axis.abbreviation.empty() ? axis.name : axis.abbreviation);
  }
  target_is_lonlat = is_geographic_degrees(td);
  // Longitude and latitude are needed to choose among candidates, to hold
  // a point to a datum change's area of use, and to warn about points
  // outside a CRS's area (from the output, when it is in degrees, where
  // nothing else needs them).
  const bool datum_areas = std::any_of(all.begin(), all.end(), [](const Candidate& c) { return !c.datum_areas.empty(); });
  const bool need_lonlat =
      all.size() > 1 || datum_areas || (!source_is_lonlat && !target_is_lonlat && (sd.area || td.area));
  if (need_lonlat && !source_is_lonlat) {
    Pj geog(proj_create(proj_ctx, "OGC:CRS84"));
    const char* opts[] = {"ALLOW_BALLPARK=YES", nullptr};  // for areas only: metres do not matter
    Pj raw(proj_create_crs_to_crs_from_pj(proj_ctx, src.get(), geog.get(), nullptr, opts));
    if (raw) to_lonlat.reset(proj_normalize_for_visualization(proj_ctx, raw.get()));
    if (!to_lonlat && (all.size() > 1 || datum_areas)) {
      throw Error(ErrorKind::io, "E_CRS", where + ": " + pair + ": PROJ cannot give " + src_name +
                                            "'s longitude and latitude, which choosing among its operations and "
                                            "holding a datum change to its area of use need");
    }
  }
  source_area.crs = src_name;
  source_area.area = sd.area;
  target_area.crs = dst_name;
  target_area.area = td.area;
}

std::vector<CrsOperationCandidate> CrsOperation::candidates() const {
  std::vector<CrsOperationCandidate> out;
  for (const auto& c : impl_->all) out.push_back(c.info);
  return out;
}

std::optional<double> CrsOperation::epoch() const { return impl_->t; }

}  // namespace geoanchor::io
