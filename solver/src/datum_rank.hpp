#pragma once
// Which combinations of a network's datum motions (translations, rotations,
// scale) its measurements and constraints leave undefined, judged against
// the network's own precision, never in metres (issue 39 point 3).
//
// The motions g (each moving the stations by 1 m RMS) are weighed by what
// the measurements tell of them against what a typical station is told:
// with A_j a measurement's whitened rows and G_j the motions at its
// unknowns,
//   told(y)  = Σ_j ‖A_j G_j y‖² + Σ_c w_c (g_c y)²   (w_c = 1/σ² of a held component)
//   could(y) = Σ_j ‖A_j‖²_F ‖G_j y‖²
//   ratio(y) = told(y) / (could(y) / n)              (n: the stations)
// could(y)/n bounds from above what a typical station is told along the
// motion (‖A_j G_j y‖ ≤ ‖A_j‖_F ‖G_j y‖), so the ratio is at most the
// square of a typical station's standard deviation over the combination's.
// It does not depend on the unit of the coordinates, nor on the number of
// stations for a datum held at one of them (a single GNSS point, one
// weighted hold).
//
// The sums are never formed: each is kept as the R factor of its rows
// stacked (a tall-skinny QR, RowsR), so that a combination nothing tells of
// comes out at rounding's level, 10⁻³² of the scale, not at the 10⁻¹⁶ at
// which the eigenvalues of a sum of squares stop.
//
// Private to solver.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace geoanchor::solver {

// The R factor (d × d, upper triangular) of a tall matrix of d columns
// given as blocks of rows, in order: RᵀR is the matrix's Gram matrix,
// computed by Householder reflections of the rows (no sum of squares). The
// same rows in the same order give the same bits.
class RowsR {
 public:
  explicit RowsR(Eigen::Index columns);
  void add(const Eigen::MatrixXd& rows);
  // Appends another's rows (by its R: the same Gram matrix).
  void add(const RowsR& other);
  // R (d × d; zero rows where fewer than d rows came).
  Eigen::MatrixXd r() const;

 private:
  void fold();
  Eigen::Index columns_;
  Eigen::MatrixXd r_;       // columns_ × columns_
  Eigen::MatrixXd buffer_;  // rows waiting to be folded into r_
  Eigen::Index buffered_ = 0;
};

// A combination's motion of the fixed components below this share of a
// typical station's motion (squared: 10⁻⁷ of the motion) is no motion of
// them (rounding leaves about 10⁻³²): held by so short a lever (fixed
// stations 0.1 mm apart in a network of a kilometre) the factorization
// would meet it at its rounding, as with a ratio below 10⁻¹⁴; it is judged
// by the measurements and weighted constraints instead.
inline constexpr double kFixedMotionSquared = 1e-14;

struct DatumRank {
  // Columns over the motions: the combinations below the threshold asked
  // for, weakest first (not normalized).
  Eigen::MatrixXd combinations;
  std::vector<double> ratio;     // told / (could / n)
  std::vector<double> measured;  // Σ_j ‖A_j G_j y‖² of the column y
  std::vector<double> weighted;  // Σ_c w_c (g_c y)²
};

// The combinations of the motions that move no fixed component (rows
// `fixed`: each fixed component's motions, m × d) and whose ratio is below
// `below`. `station_gram` is Σ over the stations' components of gᵀg (d ×
// d): n times a typical station's motion; `measured`, `weighted` and
// `reference` the R factors of the rows A_j G_j, √w_c g_c and ‖A_j‖ G_j.
DatumRank weak_combinations(const Eigen::MatrixXd& fixed, const Eigen::MatrixXd& station_gram, std::size_t stations,
                            const Eigen::MatrixXd& measured, const Eigen::MatrixXd& weighted, const Eigen::MatrixXd& reference,
                            double below);

}  // namespace geoanchor::solver
