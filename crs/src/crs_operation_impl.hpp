#pragma once
// What the parts of CrsOperation share (private to crs): PROJ's candidate
// operations for a pair, the tally of points outside an area of use, and
// the operation's state (CrsOperation::Impl), which crs_operation.cpp sets
// up, crs_operation_choice.cpp chooses from point by point,
// crs_operation_transform.cpp runs over batches and crs_operation_report.cpp
// describes.

#include <proj.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/base/number_text.hpp"
#include "geoanchor/crs/crs_operation.hpp"
#include "proj_handles.hpp"

namespace geoanchor::io {
namespace detail {

struct Candidate {
  CrsOperationCandidate info;
  Pj op;  // normalized for visualization; null when a grid is missing or PROJ cannot run it
  bool instantiable = false;
  std::string unusable;  // why PROJ cannot run it although its grids are here ("" when it can)
  // The areas of use of its datum-changing steps (not of its conversions,
  // which hold wherever their formulas do): a point it moves must lie in
  // each. Empty for a conversion.
  std::vector<CrsArea> datum_areas;
  bool holds(double lon, double lat) const {
    return std::all_of(datum_areas.begin(), datum_areas.end(), [&](const CrsArea& a) { return a.contains(lon, lat); });
  }
};

std::string joined(const std::vector<std::string>& v, const char* sep = ", ");
std::string accuracy_text(const std::optional<double>& a);

struct ListDeleter {
  void operator()(PJ_OBJ_LIST* l) const { proj_list_destroy(l); }
};
using PjList = std::unique_ptr<PJ_OBJ_LIST, ListDeleter>;

// PROJ's candidate operations for the pair. With `grids` =
// PROJ_GRID_AVAILABILITY_DISCARD_OPERATION_IF_MISSING_GRID they are exactly
// those proj_create_crs_to_crs chooses among (network access off), and
// `keep` receives PROJ's list for proj_get_suggested_operation; with
// PROJ_GRID_AVAILABILITY_IGNORED they include the operations whose grids
// are not on the machine.
std::vector<Candidate> list_operations(PJ_CONTEXT* ctx, PJ* src, PJ* dst, bool allow_ballpark,
                                       PROJ_GRID_AVAILABILITY_USE grid_use, PjList* keep = nullptr);

// Points outside an area of use: counted, the first kept.
struct AreaTally {
  std::string crs;
  std::optional<CrsArea> area;
  std::size_t outside = 0, seen = 0;
  std::string first;
  void check(double lon, double lat, const std::function<std::string()>& name) {
    ++seen;
    if (!area || area->contains(lon, lat)) return;
    if (outside++ == 0) first = name() + " (latitude " + format_shortest(lat) + "°, longitude " + format_shortest(lon) + "°)";
  }
  std::optional<std::string> warning() const {
    if (outside == 0) return std::nullopt;
    return std::to_string(outside) + " of " + std::to_string(seen) + " points lie outside the area of use of " + crs +
           " (" + area->name + ": longitude " + format_shortest(area->west_deg) + "° to " +
           format_shortest(area->east_deg) + "°, latitude " + format_shortest(area->south_deg) + "° to " +
           format_shortest(area->north_deg) + "°); the first is " + first;
  }
};

}  // namespace detail

struct CrsOperation::Impl {
  detail::PjContext ctx;
  detail::PjList available;  // PROJ's list of the candidates it chooses among (the first `available_count` of `all`)
  std::size_t available_count = 0;
  detail::Pj src, dst;
  // A geocentric source with several candidates is chosen for from its
  // geographic 3D form (PROJ 9.1 chooses a geocentric point's operation as
  // if it were at latitude 0): `pre` converts to it, exactly, first.
  detail::Pj pre;
  std::string src_name, dst_name;
  std::string where;
  Options options;
  // PROJ's candidates with their grids on the machine, in PROJ's order,
  // then those whose grids are missing (never used; named when better).
  std::vector<detail::Candidate> all;
  bool source_swapped = false;  // the source's own axis order is not the visualisation order
  std::optional<double> t;
  // A time-dependent operation between CRSs that state no epoch: whether its
  // result depends on the epoch is checked on the points (issue 40 point 5).
  std::string epoch_probe;      // the operation's name; empty: no check due
  std::size_t epoch_probed = 0;  // points checked so
  bool probing = false;         // inside the check
  double epoch_free_worst_m = 0.0;  // the largest difference the check saw
  std::vector<std::string> notes;
  detail::Pj to_lonlat;  // source → geographic longitude/latitude, degrees (for choices and areas)
  bool source_is_lonlat = false, target_is_lonlat = false;
  std::vector<std::string> axis_labels;  // the source's axes in the order the coordinates are given ("Lon", "Lat", "h")
  bool source_is_planar = false;  // a projected source: a box in its plane bounds a batch (not so for x, y, z)
  detail::AreaTally source_area, target_area;  // points outside either CRS's area of use: warned
  std::size_t fallbacks = 0;
  std::string first_fallback;
  std::set<std::string> fallback_reasons;  // why the better operations were not used: missing grids named
  // Points whose PROJ choice was set aside for one whose area holds them.
  std::size_t set_aside = 0;
  std::string first_set_aside;

  // The candidate PROJ would use at (lon, lat), from index `from` on, and a
  // better-ranked one whose grid is missing (when there is one).
  struct Choice {
    std::optional<std::size_t> use, missing_better;
    // PROJ's own choice, set aside: its datum change does not hold the point
    // (PROJ judges areas by a box in the source CRS).
    std::optional<std::size_t> set_aside;
  };
  // PROJ's own choice for a point (proj_get_suggested_operation on its list,
  // given the point in the source's own axis order), and a candidate with a
  // missing grid whose area holds (lon, lat) and whose accuracy is better.
  Choice choose(double a, double b, double c, double lon, double lat, bool lonlat_known) const;
  // After a candidate failed at a point: the best other available one that
  // holds it (--allow-fallback), skipping `tried`.
  std::optional<std::size_t> fallback(double lon, double lat, const std::vector<std::size_t>& tried) const;
  // Whether every point of a batch in a projected source lies inside each
  // of `areas` (see the definition).
  bool batch_inside(const std::vector<const CrsArea*>& areas, const std::vector<double>& a, const std::vector<double>& b) const;
  // The one candidate every point in a longitude/latitude box takes (see
  // the definition), from PROJ's choice at one of them: a0, b0, c0 in the
  // source's coordinates, at lon0, lat0.
  struct Box {
    double west, south, east, north;
  };
  std::optional<std::size_t> uniform_choice(const Box& box, double a0, double b0, double c0, double lon0, double lat0) const;
  // A batch's box, when it has one (nullopt if a point's longitude or
  // latitude is not finite).
  static std::optional<Box> box_of(const std::vector<double>& lon, const std::vector<double>& lat);
  // Which of the candidates' areas (areas_chosen_by) hold a point, a bit
  // each: PROJ's choice and choose()'s checks depend on nothing else, so
  // points with one signature share one Choice (choices_by_signature).
  using Signature = std::vector<std::uint64_t>;
  std::vector<const CrsArea*> areas_chosen_by;
  std::vector<std::pair<Signature, Choice>> choices_by_signature;
  void signature(double lon, double lat, Signature& bits) const {
    bits.assign((areas_chosen_by.size() + 63) / 64, 0);
    for (std::size_t k = 0; k < areas_chosen_by.size(); ++k) {
      bits[k / 64] |= static_cast<std::uint64_t>(areas_chosen_by[k]->contains(lon, lat)) << (k % 64);
    }
  }

  // The constructor's steps, in order (crs_operation.cpp). `pair` names
  // both CRSs in messages ("A → B").
  void settle_epoch(const Crs& source, const Crs& target, bool same_datum, const std::string& pair);
  CrsDescription list_candidates(const CrsDescription& sd, const CrsDescription& td, bool same_datum,
                                 const std::string& pair);
  void refuse_unusable(const std::string& pair) const;
  void check_ensembles(const CrsDescription& sd, const CrsDescription& td, bool same_datum, const std::string& pair);
  void refuse_missing_grids(const std::string& pair) const;
  void check_time_dependence(const Crs& source, const Crs& target, const std::string& pair);
  void hash_grids();
  void prepare_lonlat(const CrsDescription& chosen_from, const CrsDescription& sd, const CrsDescription& td,
                      const std::string& pair);

  // transform() of points that count (crs_operation_transform.cpp), and
  // one batch of them as it runs.
  void transform_counted(double* a, double* b, double* c, std::size_t n,
                         const std::function<std::string(std::size_t)>& point_name);
  struct Batch;
};

}  // namespace geoanchor::io
