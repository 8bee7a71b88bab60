#pragma once
// PROJ as the independent reference in tests, through its C API.
// A ProjPipeline wraps one PROJ string; coordinates are passed in the units
// PROJ's operations use internally (radians for angles, metres otherwise).

#include <Eigen/Core>

#include <string>

struct pj_ctx;
struct PJconsts;

namespace geoanchor::testing {

class ProjPipeline {
 public:
  explicit ProjPipeline(const std::string& definition);
  // The operation PROJ itself chooses between two CRSs (proj_create_crs_to_crs;
  // for dynamic CRSs the coordinate epoch is each point's t).
  static ProjPipeline crs_to_crs(const std::string& source_crs, const std::string& target_crs);
  // PROJ's description of the operation (for messages and docs).
  std::string description() const;
  ~ProjPipeline();
  ProjPipeline(const ProjPipeline&) = delete;
  ProjPipeline& operator=(const ProjPipeline&) = delete;

  // Forward and inverse of (x, y, z) at time t (decimal year; ignored by
  // operations that are not time-dependent). NaN if PROJ reports an error;
  // a NaN that PROJ does not report as an error fails the current test.
  Eigen::Vector3d forward(const Eigen::Vector3d& xyz, double t = 0.0) const;
  Eigen::Vector3d inverse(const Eigen::Vector3d& xyz, double t = 0.0) const;

 private:
  Eigen::Vector3d trans(const Eigen::Vector3d& xyz, double t, int direction) const;
  ProjPipeline(pj_ctx* ctx, PJconsts* pj, std::string definition);
  std::string definition_;
  pj_ctx* ctx_;
  PJconsts* pj_;
};

// Whether PROJ parses `text` (WKT, PROJJSON, ...) as a coordinate reference system.
bool proj_parses_crs(const std::string& text);

// Degrees to radians the way PROJ's own tools do (proj_torad).
double proj_radians(double degrees);
double proj_degrees(double radians);

}  // namespace geoanchor::testing
