#pragma once
// What the fit tests share (helmert_fit_test.cpp, enu_origin_fit_test.cpp):
// control points generated through PROJ and published parameter sets.
// Test-only: one definition for every test file that includes it (inline).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>
#include <map>
#include <random>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/solver/helmert_fit.hpp"
#include "generated_control.hpp"
#include "proj_reference.hpp"
#include "test_support.hpp"

namespace geoanchor::solver {
namespace helmert_fit_fixture {

using geodesy::Angle;
using geodesy::ControlPoint;
using geodesy::ControlSet;
using geodesy::DecimalYear;
using geodesy::EcefPosition;
using testing::ProjPipeline;

constexpr double kTranslationTol_m = 1e-6;   // issue acceptance
constexpr double kRotationTol_arcsec = 1e-5; // issue acceptance
constexpr double kScaleTol_ppm = 1e-5;       // issue acceptance
constexpr double kResidualTol_m = 1e-6;      // issue acceptance
constexpr double kClosedFormRelTol = 1e-9;   // issue acceptance: Ceres vs Umeyama
constexpr double kDecorrelatedTol = 0.2;     // |corr(t, r)| about the centroid of a symmetric-ish network
constexpr double kGeocentricCorrelatedFloor = 0.5;  // geocentric t and r of a 3 km network: strongly correlated
constexpr double kSameFitSigma0Tol = 1e-9;   // one fit, two parametrisations

using testing::control_from_proj;
using testing::region;

inline double param(const FitResult& r, const std::string& name) {
  for (const auto& p : r.parameters) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << "no parameter " << name;
  return 0.0;
}

inline ControlSet tiny(std::vector<Eigen::Vector3d> offsets) {
  ControlSet set;
  set.source_name = "c.csv";
  const Eigen::Vector3d base(4270803.44, 640437.85, 4678617.58);
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    ControlPoint p;
    p.id = "P" + std::to_string(i);
    p.line = i + 2;
    p.source = EcefPosition(Eigen::Vector3d(base + offsets[i]));
    p.target = EcefPosition(Eigen::Vector3d(base + offsets[i] + Eigen::Vector3d(1, 2, 3)));
    p.source_cov_m2 = p.target_cov_m2 = Eigen::Matrix3d::Identity() * 1e-4;
    set.points.push_back(p);
  }
  return set;
}

inline std::string rejection(const ControlSet& set, FitOptions o) {
  try {
    fit_helmert(set, o);
  } catch (const Error& e) {
    return e.code() + ": " + e.what();
  }
  return "accepted";
}

struct Published {
  const char* name;
  const char* proj;  // a PROJ operation, ECEF in and out
  FitModel model;
  Convention convention;
  std::map<std::string, double> expected;  // parameters in the named convention and units
  double lat, lon, radius_deg;
  std::vector<double> epochs;
};

}  // namespace helmert_fit_fixture
}  // namespace geoanchor::solver
