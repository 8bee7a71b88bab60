#pragma once
// Coordinates from one CRS to another through PROJ, over whole arrays.
//
// The operation is PROJ's choice for the pair: the candidates
// proj_create_crs_to_crs chooses among (proj_create_operations, grids
// missing discarded) and, per point, the one proj_get_suggested_operation
// names (a geocentric source is chosen for from its latitude, longitude and
// height: PROJ 9.1.1 would choose as if at latitude 0), with three rules
// that PROJ leaves to the caller:
//  - an operation PROJ calls a ballpark one (a datum change of unknown
//    accuracy) is never used: no operation is an error;
//  - a better-ranked operation whose grid is not on the machine is an error
//    naming the grid and where PROJ looked for it, never a silent fallback
//    to a worse one (unless `allow_fallback`);
//  - a point a grid does not cover is an error naming the grid and the
//    point (unless `allow_fallback`: then the next operation that holds it).
// Coordinates are in each CRS's own units, in the order PROJ's
// proj_normalize_for_visualization gives (longitude or easting first).

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/base/hash.hpp"
#include "geoanchor/crs/crs.hpp"

namespace geoanchor::io {

struct CrsGridFile {
  std::string name;  // as PROJ's database names it ("ch_swisstopo_CHENyx06a.tif")
  std::string path;  // the file used on this machine ("" when missing)
  std::string sha256;
  bool available = false;
};

struct CrsOperationCandidate {
  std::string name;        // PROJ's name of the operation
  std::string identifier;  // "EPSG:1234" when PROJ names one
  std::optional<double> accuracy_m;  // nullopt: PROJ states none (a conversion is exact: 0)
  std::vector<CrsGridFile> grids;
  std::string proj_string;  // the pipeline PROJ runs
  bool time_dependent = false;
  std::optional<CrsArea> area;
  std::size_t points = 0;  // how many points it moved
};


struct CrsOperationOptions {
  bool allow_fallback = false;  // --allow-fallback: a worse operation where a grid is missing or does not cover
  // Where the grid files' hashes are kept between operations (a batch's
  // tiles); null: each operation hashes its grids itself.
  FileHashCache* grid_hashes = nullptr;
};

class CrsOperation {
 public:
  using Options = CrsOperationOptions;

  // Throws geoanchor::Error (input) naming `where` and both CRSs: no
  // operation but a ballpark one (E_CRS_NO_OPERATION); the best operation
  // needs a grid that is not on the machine (E_CRS_GRID_MISSING, naming the
  // file and PROJ's search paths); a datum change where a side is an
  // ensemble (E_CRS_ENSEMBLE, naming its members and accuracy); a dynamic
  // CRS without its epoch where the datum changes, or two dynamic CRSs at
  // different epochs (E_EPOCH_MISSING, E_CRS_EPOCH).
  CrsOperation(const Crs& source, const Crs& target, std::string_view where, Options options = {});
  ~CrsOperation();
  CrsOperation(const CrsOperation&) = delete;
  CrsOperation& operator=(const CrsOperation&) = delete;

  // Transforms n points in place (`c` may be null: 2-D). `point_name(i)`
  // names point i in errors ("in.csv:12"). Throws geoanchor::Error (input,
  // E_CRS_TRANSFORM) naming the point, its coordinates and the operation
  // for a point the operation cannot move (outside a grid, outside the
  // projection's domain); nothing non-finite is ever returned.
  // With Count::no the points are not counted in candidates() nor in the
  // warnings (points that only serve a computation, such as a Jacobian's
  // neighbours).
  enum class Count { yes, no };
  void transform(double* a, double* b, double* c, std::size_t n, const std::function<std::string(std::size_t)>& point_name,
                 Count count = Count::yes);

  // An estimate for a few points (a tile's bounding-box corners): PROJ's
  // best-ranked operation, no per-point choice, nothing counted or warned;
  // a point it cannot move becomes NaN. Never for output.
  void estimate(double* a, double* b, double* c, std::size_t n) const;

  std::vector<CrsOperationCandidate> candidates() const;
  // The coordinate epoch the operation is evaluated at (PROJ's t), if any.
  std::optional<double> epoch() const;
  // Warnings gathered so far: an ensemble where the realization cannot
  // matter, points outside a CRS's area of use (counted, the first named),
  // a fallback used.
  std::vector<std::string> warnings() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What an output records of the operation (JSON text): PROJ's version, the
// epoch it was evaluated at, and every candidate with its accuracy, grid
// files (path and SHA-256 where on this machine) and the points it moved.
std::string operation_record_json(const CrsOperation& op);

}  // namespace geoanchor::io
