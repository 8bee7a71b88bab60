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
  // operations that are not time-dependent). A reference that cannot give
  // a value must not pass a comparison quietly, so when PROJ reports an
  // error for the point (proj_errno != 0 or a HUGE_VAL result) the current
  // test fails, naming the pipeline, the point and PROJ's error string, and
  // the result is NaN; a NaN that PROJ does not report as an error for
  // finite input fails the test too. A test that probes PROJ's own
  // failures asks for them with try_forward / try_inverse.
  Eigen::Vector3d forward(const Eigen::Vector3d& xyz, double t = 0.0) const;
  Eigen::Vector3d inverse(const Eigen::Vector3d& xyz, double t = 0.0) const;

  // The explicit form, for points where PROJ is expected (or allowed) to
  // fail: PROJ's result, or its error, without failing the test.
  struct Result {
    Eigen::Vector3d xyz;  // NaN when PROJ reported an error
    int proj_errno = 0;   // 0: no error
    std::string error;    // PROJ's error string, empty when none
    bool ok() const { return proj_errno == 0; }
  };
  Result try_forward(const Eigen::Vector3d& xyz, double t = 0.0) const;
  Result try_inverse(const Eigen::Vector3d& xyz, double t = 0.0) const;

 private:
  Result trans(const Eigen::Vector3d& xyz, double t, int direction) const;
  Eigen::Vector3d checked(const Eigen::Vector3d& xyz, double t, int direction) const;
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
