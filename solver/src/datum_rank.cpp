// The datum's undefined combinations, from the network's own precision (datum_rank.hpp).

#include "datum_rank.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <Eigen/SVD>

#include <stdexcept>

namespace geoanchor::solver {
namespace {

// Rows folded into R at a time: a Householder QR of (d + this) × d.
constexpr Eigen::Index kBufferRows = 256;

// The upper triangle of a QR of `stacked` as a d × d matrix.
Eigen::MatrixXd r_of(const Eigen::MatrixXd& stacked, Eigen::Index d) {
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(d, d);
  if (stacked.rows() == 0) return r;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
  const Eigen::Index rows = std::min(stacked.rows(), d);
  r.topRows(rows) = qr.matrixQR().topRows(rows).triangularView<Eigen::Upper>();
  return r;
}

}  // namespace

RowsR::RowsR(Eigen::Index columns)
    : columns_(columns), r_(Eigen::MatrixXd::Zero(columns, columns)), buffer_(kBufferRows, columns) {}

void RowsR::add(const Eigen::MatrixXd& rows) {
  Eigen::Index at = 0;
  while (at < rows.rows()) {
    const Eigen::Index take = std::min(rows.rows() - at, kBufferRows - buffered_);
    buffer_.middleRows(buffered_, take) = rows.middleRows(at, take);
    buffered_ += take;
    at += take;
    if (buffered_ == kBufferRows) fold();
  }
}

void RowsR::add(const RowsR& other) { add(other.r()); }

void RowsR::fold() {
  if (buffered_ == 0) return;
  Eigen::MatrixXd stacked(columns_ + buffered_, columns_);
  stacked << r_, buffer_.topRows(buffered_);
  r_ = r_of(stacked, columns_);
  buffered_ = 0;
}

Eigen::MatrixXd RowsR::r() const {
  if (buffered_ == 0) return r_;
  Eigen::MatrixXd stacked(columns_ + buffered_, columns_);
  stacked << r_, buffer_.topRows(buffered_);
  return r_of(stacked, columns_);
}

DatumRank weak_combinations(const Eigen::MatrixXd& fixed, const Eigen::MatrixXd& station_gram, std::size_t stations,
                            const Eigen::MatrixXd& measured, const Eigen::MatrixXd& weighted, const Eigen::MatrixXd& reference,
                            double below) {
  const Eigen::Index d = station_gram.rows();
  const double n = static_cast<double>(std::max<std::size_t>(stations, 1));
  DatumRank out;
  out.combinations.resize(d, 0);
  if (d == 0) return out;
  // Coordinates in which a unit vector moves a typical station by 1 (Tn = L Lᵀ; y = L⁻ᵀ v).
  const Eigen::LLT<Eigen::MatrixXd> typical(station_gram / n);
  if (typical.info() != Eigen::Success) throw std::logic_error("weak_combinations: a datum motion moves no station");
  const Eigen::MatrixXd to_motions = typical.matrixU().solve(Eigen::MatrixXd::Identity(d, d));  // L⁻ᵀ
  // The combinations that move no fixed component (a fixed component
  // defines any motion of it): from the singular values of the fixed rows
  // in those coordinates, never their squares summed.
  Eigen::MatrixXd u = to_motions;
  if (fixed.rows() > 0) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(fixed * to_motions, Eigen::ComputeFullV);
    const Eigen::VectorXd& s = svd.singularValues();
    std::vector<Eigen::Index> free;
    for (Eigen::Index k = 0; k < d; ++k) {
      if (k >= s.size() || s(k) * s(k) < kFixedMotionSquared) free.push_back(k);
    }
    u.resize(d, static_cast<Eigen::Index>(free.size()));
    for (std::size_t k = 0; k < free.size(); ++k) u.col(static_cast<Eigen::Index>(k)) = to_motions * svd.matrixV().col(free[k]);
  }
  const Eigen::Index f = u.cols();
  if (f == 0) return out;
  // Among them, the generalized singular values of (told, could): with
  // could's rows R_ref U = Q R2, the singular values of [R_m U; R_w U] R2⁻¹.
  const Eigen::MatrixXd r2 = r_of(reference * u, f);
  for (Eigen::Index k = 0; k < f; ++k) {
    if (!(std::abs(r2(k, k)) > 0.0)) throw std::logic_error("weak_combinations: a datum motion moves no measured unknown");
  }
  Eigen::MatrixXd told(2 * d, f);
  told << measured * u, weighted * u;
  const Eigen::MatrixXd x = r2.triangularView<Eigen::Upper>().transpose().solve(told.transpose()).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(x, Eigen::ComputeFullV);
  const Eigen::VectorXd& sigma = svd.singularValues();
  std::vector<Eigen::VectorXd> keep;
  for (Eigen::Index k = f - 1; k >= 0; --k) {  // weakest first
    const double s = k < sigma.size() ? sigma(k) : 0.0;
    const double ratio = n * s * s;
    if (!(ratio < below)) break;
    const Eigen::VectorXd y = u * r2.triangularView<Eigen::Upper>().solve(svd.matrixV().col(k));
    keep.push_back(y);
    out.ratio.push_back(ratio);
    out.measured.push_back((measured * y).squaredNorm());
    out.weighted.push_back((weighted * y).squaredNorm());
  }
  out.combinations.resize(d, static_cast<Eigen::Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k) out.combinations.col(static_cast<Eigen::Index>(k)) = keep[k];
  return out;
}

}  // namespace geoanchor::solver
