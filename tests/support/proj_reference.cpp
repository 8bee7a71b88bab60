#include "proj_reference.hpp"

#include <proj.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace geoanchor::testing {

ProjPipeline::ProjPipeline(const std::string& definition)
    : definition_(definition), ctx_(proj_context_create()), pj_(nullptr) {
  pj_ = proj_create(ctx_, definition.c_str());
  if (!pj_) {
    const std::string why = proj_context_errno_string(ctx_, proj_context_errno(ctx_));
    proj_context_destroy(ctx_);
    throw std::runtime_error("PROJ rejected '" + definition + "': " + why);
  }
}

ProjPipeline::ProjPipeline(pj_ctx* ctx, PJconsts* pj, std::string definition)
    : definition_(std::move(definition)), ctx_(ctx), pj_(pj) {}

ProjPipeline ProjPipeline::crs_to_crs(const std::string& source_crs, const std::string& target_crs) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* pj = proj_create_crs_to_crs(ctx, source_crs.c_str(), target_crs.c_str(), nullptr);
  if (!pj) {
    const std::string why = proj_context_errno_string(ctx, proj_context_errno(ctx));
    proj_context_destroy(ctx);
    throw std::runtime_error("PROJ has no operation from " + source_crs + " to " + target_crs + ": " + why);
  }
  return ProjPipeline(ctx, pj, source_crs + " -> " + target_crs);
}

std::string ProjPipeline::description() const {
  const PJ_PROJ_INFO info = proj_pj_info(pj_);
  return info.description ? info.description : definition_;
}

ProjPipeline::~ProjPipeline() {
  proj_destroy(pj_);
  proj_context_destroy(ctx_);
}

namespace {

// PROJ 9.1.1's topocentric step does not carry the time coordinate to the
// next step of a pipeline: that step reads an uninitialised stack value
// (valgrind: "created by a stack allocation" in libproj; cct prints t = 0
// after a topocentric step). Depending on the garbage, even a static Helmert
// returns NaN for every point (0 × NaN in its time term). Zeroing the stack
// it is about to use makes that time 0 every call, which static steps
// ignore; time-dependent steps after topocentric need a pipeline of their own.
[[gnu::noinline]] void scrub_stack() {
  volatile unsigned char buf[4096];
  for (std::size_t i = 0; i < sizeof buf; ++i) buf[i] = 0;
}

}  // namespace

ProjPipeline::Result ProjPipeline::trans(const Eigen::Vector3d& xyz, double t, int direction) const {
  PJ_COORD c = proj_coord(xyz.x(), xyz.y(), xyz.z(), t);
  proj_errno_reset(pj_);
  scrub_stack();
  const PJ_COORD r = proj_trans(pj_, direction > 0 ? PJ_FWD : PJ_INV, c);
  Result out;
  out.proj_errno = proj_errno(pj_);
  const bool huge = r.xyzt.x == HUGE_VAL || r.xyzt.y == HUGE_VAL || r.xyzt.z == HUGE_VAL;
  if (out.proj_errno == 0 && huge) out.proj_errno = -1;  // an error PROJ did not number
  if (out.proj_errno != 0) {
    const char* why = out.proj_errno > 0 ? proj_context_errno_string(ctx_, out.proj_errno) : nullptr;
    out.error = why ? why : "HUGE_VAL result without an error number";
    const double nan = std::numeric_limits<double>::quiet_NaN();
    out.xyz = Eigen::Vector3d(nan, nan, nan);
    return out;
  }
  out.xyz = Eigen::Vector3d(r.xyzt.x, r.xyzt.y, r.xyzt.z);
  return out;
}

namespace {

std::string point_text(const Eigen::Vector3d& xyz, double t) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.17g, %.17g, %.17g, t=%.17g)", xyz.x(), xyz.y(), xyz.z(), t);
  return buf;
}

}  // namespace

Eigen::Vector3d ProjPipeline::checked(const Eigen::Vector3d& xyz, double t, int direction) const {
  const Result r = trans(xyz, t, direction);
  const char* way = direction > 0 ? "forward" : "inverse";
  if (!r.ok()) {
    ADD_FAILURE() << "PROJ reported an error (" << r.proj_errno << ": " << r.error << ") for the " << way << " of "
                  << point_text(xyz, t) << " through '" << definition_
                  << "'; a test that expects PROJ to fail there uses try_" << way;
  } else if (xyz.allFinite() && !r.xyz.allFinite()) {
    // A reference that silently returns NaN would let a careless worst case
    // pass; PROJ 9.1.1 was seen to do so for a whole PJ now and then
    // (valgrind: uninitialised reads in proj_trans).
    ADD_FAILURE() << "PROJ returned " << r.xyz.transpose() << " without an error for the finite " << way << " of "
                  << point_text(xyz, t) << " through '" << definition_ << "'";
  }
  return r.xyz;
}

Eigen::Vector3d ProjPipeline::forward(const Eigen::Vector3d& xyz, double t) const { return checked(xyz, t, +1); }
Eigen::Vector3d ProjPipeline::inverse(const Eigen::Vector3d& xyz, double t) const { return checked(xyz, t, -1); }
ProjPipeline::Result ProjPipeline::try_forward(const Eigen::Vector3d& xyz, double t) const { return trans(xyz, t, +1); }
ProjPipeline::Result ProjPipeline::try_inverse(const Eigen::Vector3d& xyz, double t) const { return trans(xyz, t, -1); }

bool proj_parses_crs(const std::string& text) {
  PJ_CONTEXT* ctx = proj_context_create();
  PJ* crs = proj_create(ctx, text.c_str());
  const bool ok = crs != nullptr && proj_is_crs(crs) != 0;
  proj_destroy(crs);
  proj_context_destroy(ctx);
  return ok;
}

double proj_radians(double degrees) { return proj_torad(degrees); }
double proj_degrees(double radians) { return proj_todeg(radians); }

}  // namespace geoanchor::testing
