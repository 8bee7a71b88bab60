#pragma once
// Worst cases of accuracy comparisons that cannot drop a NaN.
//
// `w = std::max(w, d)` keeps `w` when `d` is NaN (every
// comparison with NaN is false), so a comparison whose code under test
// returns NaN for every point ends with w = 0 and passes. Every
// accuracy comparison in tests/ and bench/ goes through this header
// instead: a NaN anywhere makes the worst case NaN, and a worst case of no
// comparison at all is NaN too (a loop that never ran proves nothing).
//
// No GoogleTest here, so that bench/ can use it; the assertion
// (EXPECT_WORST_WITHIN) is in test_support.hpp.

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <string>

namespace geoanchor::testing {

// The larger of a and b; NaN if either is NaN (std::max(a, NaN) is a).
inline double nan_max(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::numeric_limits<double>::quiet_NaN();
  return a < b ? b : a;
}

// The largest |component| of a vector or matrix; NaN if any component is
// NaN (Eigen's default maxCoeff may drop a NaN).
template <class Derived>
double max_abs_component(const Eigen::MatrixBase<Derived>& v) {
  double worst = 0.0;
  for (Eigen::Index c = 0; c < v.cols(); ++c) {
    for (Eigen::Index r = 0; r < v.rows(); ++r) worst = nan_max(worst, std::abs(static_cast<double>(v(r, c))));
  }
  return worst;
}

// The worst of a series of non-negative differences (distances, |errors|,
// ratios to a tolerance), with where it occurred and how many were NaN.
class WorstCase {
 public:
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

  // One comparison's difference; `where` labels it in messages (a point's
  // index; by default the number of values added before it).
  void add(double d, std::size_t where = npos) {
    const std::size_t at = where == npos ? count_ : where;
    ++count_;
    if (std::isnan(d)) {
      if (nan_count_++ == 0) first_nan_at_ = at;
      return;
    }
    if (count_ - nan_count_ == 1 || d > largest_) largest_ = d, largest_at_ = at;
  }
  // Every comparison of another worst case (e.g. one per ellipsoid).
  void add(const WorstCase& other) {
    if (other.nan_count_ > 0 && nan_count_ == 0) first_nan_at_ = other.first_nan_at_;
    if (other.count_ > other.nan_count_ && (count_ == nan_count_ || other.largest_ > largest_)) {
      largest_ = other.largest_, largest_at_ = other.largest_at_;
    }
    count_ += other.count_;
    nan_count_ += other.nan_count_;
  }

  // The largest difference; NaN if any was NaN or none was added.
  double value() const {
    return nan_count_ > 0 || count_ == 0 ? std::numeric_limits<double>::quiet_NaN() : largest_;
  }
  std::size_t count() const { return count_; }
  std::size_t nan_count() const { return nan_count_; }
  // Where the largest finite difference was (npos if there was none).
  std::size_t largest_at() const { return count_ > nan_count_ ? largest_at_ : npos; }
  std::size_t first_nan_at() const { return nan_count_ > 0 ? first_nan_at_ : npos; }

  // Whether every difference is a number and at most `tol`.
  bool within(double tol) const { return value() <= tol; }

  // E.g. "2.310e-09 at #17 of 1000", "NaN: 1000 of 1000 are NaN, the first at #0",
  // "no comparison was made".
  std::string describe() const {
    if (count_ == 0) return "no comparison was made";
    char buf[160];
    if (nan_count_ > 0) {
      std::snprintf(buf, sizeof buf, "NaN: %zu of %zu are NaN, the first at #%zu", nan_count_, count_, first_nan_at_);
      std::string out = buf;
      if (count_ > nan_count_) {
        std::snprintf(buf, sizeof buf, " (largest of the others %.3e at #%zu)", largest_, largest_at_);
        out += buf;
      }
      return out;
    }
    std::snprintf(buf, sizeof buf, "%.3e at #%zu of %zu", largest_, largest_at_, count_);
    return buf;
  }

 private:
  std::size_t count_ = 0, nan_count_ = 0;
  double largest_ = 0.0;
  std::size_t largest_at_ = npos, first_nan_at_ = npos;
};

}  // namespace geoanchor::testing
