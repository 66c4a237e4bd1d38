#pragma once
// Reader for pose graphs in the g2o text format: 3-D (VERTEX_SE3:QUAT / EDGE_SE3:QUAT), as
// distributed with SE-Sync (Rosen et al.) and used by g2o, GTSAM, iSAM and SLAM++, and planar
// (VERTEX_SE2 / EDGE_SE2, e.g. the Intel, M3500 and Manhattan graphs) lifted to 3-D; and the
// assembly of the information matrix Lambda = sum_e H_e^T Omega_e H_e of such a graph.
//
// Conversions to navd's conventions (core/README.md):
//  * Poses become Vec6 [x y z roll pitch heading] with Z-Y-X Euler angles
//    (R = Rz(heading) Ry(pitch) Rx(roll)) from the unit quaternion (qx qy qz qw).
//  * Quaternions whose norm differs from 1 by at most kQuaternionNormTolerance are normalised;
//    others are rejected.
//  * g2o's EdgeSE3 error is e = toVectorMQT(Z^-1 * (X_i^-1 X_j)) = [t_err; qvec_err], i.e. the
//    translation of the residual transform (in the measurement frame) and the vector part of
//    its unit quaternion (w >= 0), which is ~ dtheta/2 for a small body-frame rotation dtheta.
//    The file's 6x6 information Omega_g2o is on that error. We re-express it on our relative
//    pose parameters y = [t_ij; rpy_ij] (geometry/pose.h tail_to_tail) at the measurement z:
//        Omega = G^T Omega_g2o G,   G = d e / d y |_{y=z} = blockdiag(R_z^T, 0.5 * J2^-1(rpy_z)),
//    with J2^-1 the Euler-rate-to-body-rate matrix (rotation.h euler_rate_matrix_inverse).
//    First order: exact at the measurement, which is where a Gaussian on e is linearised.
//  * Vertex ids: any distinct non-negative integers, in any order. Vertices are stored sorted
//    by id and `index` of a vertex is its position in that order (0..N-1); edges carry both the
//    file ids and the indices. When the file's ids are already 0..N-1 the two coincide.
//
//  * Planar graphs are lifted: a pose (x, y, theta) becomes [x y 0 0 0 theta]. g2o's EdgeSE2
//    error [R_z^T (t - t_z); theta - theta_z] is EdgeSE3's [t_err; qvec_err] in the plane with
//    qvec_z = theta/2, so its 3x3 information Omega_2 becomes Omega_g2o (6x6) with the theta
//    row and column scaled by 2; the out-of-plane axes, which the file does not constrain,
//    get information as strong as the in-plane ones (z: the mean of Omega_2's x and y
//    entries; qvec_x and qvec_y: its qvec_z entry) and no correlation with them. At planar
//    poses z, roll and pitch decouple from x, y and heading to first order (a rotation about
//    x or y moves an in-plane vector only along z), so the in-plane marginals are those of
//    the planar graph (test: G2o.LiftedPlanarMarginalsEqualThePlanarGraphs). A file mixing
//    planar and 3-D elements is an error.
//
// Lines: blank lines and lines starting with '#' are ignored. FIX lines are read and their
// ids checked, and otherwise ignored: the gauge is the prior on vertex index 0
// (AssemblyOptions). Any other tag is an error.
// All malformed input throws G2oError with "source:line: reason".

#include <Eigen/SparseCore>
#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/geometry/types.h"

namespace nav::core {

/// |‖q‖ - 1| above this rejects a quaternion; below it q is normalised. Files print about 7
/// significant digits, so honest quaternions are within ~1e-6 of unit norm.
inline constexpr double kQuaternionNormTolerance = 1e-3;

/// Malformed g2o input. what() = "<source>:<line>: <reason>".
class G2oError : public std::runtime_error {
 public:
  G2oError(const std::string& source, int line, const std::string& reason);
  int line() const { return line_; }

 private:
  int line_;
};

struct G2oVertex {
  int id = 0;  ///< id in the file
  Vec6 pose;   ///< [x y z roll pitch heading] of the vertex in the world frame
};

struct G2oEdge {
  int from = 0;          ///< file id of vertex i (the edge measures j in the frame of i)
  int to = 0;            ///< file id of vertex j
  int from_index = 0;    ///< index of vertex i in PoseGraph::vertices
  int to_index = 0;      ///< index of vertex j in PoseGraph::vertices
  Vec6 measurement;      ///< x_ij = [t_ij; rpy_ij] (tail_to_tail convention, geometry/pose.h)
  Mat6 information;      ///< on our [x y z roll pitch heading] parameters (converted, see above)
  Mat6 information_g2o;  ///< on g2o's EdgeSE3 [t; qvec] error: the file's, or lifted if planar
  int line = 0;          ///< line number in the source (1-based)
};

struct PoseGraph {
  std::vector<G2oVertex> vertices;  ///< sorted by id; index = position
  std::vector<G2oEdge> edges;       ///< in file order
  bool planar = false;              ///< read from VERTEX_SE2 / EDGE_SE2 and lifted (above)
};

/// Parses a whole g2o stream. `source_name` is only used in error messages.
PoseGraph read_g2o(std::istream& in, const std::string& source_name);
/// Opens and parses a file; a file that cannot be opened throws G2oError (line 0).
PoseGraph read_g2o(const std::string& path);

/// Jacobian G = d e_g2o / d y of g2o's EdgeSE3 error with respect to our relative pose
/// parameters at the measurement y = z (see the file comment). Exposed for tests.
Mat6 g2o_error_jacobian(const Vec6& measurement);

/// How the information matrix of a pose graph is assembled.
struct AssemblyOptions {
  /// Prior on vertex index 0 (gauge): information added to its diagonal block, on
  /// [x y z roll pitch heading]. Without it Lambda is singular (a pose graph only constrains
  /// relative poses). Default: sigma 1 mm and 1 mrad, i.e. diag(1e6), a near-anchor that
  /// leaves the conditioning usable for CHOLMOD and for CG.
  Mat6 prior_information = Mat6::Identity() * 1e6;
};

/// Lambda = P + sum_e H_e^T Omega_e H_e with block_dim 6, block (a, b) for vertex indices a, b.
/// H_e = [d x_ij/d x_i | d x_ij/d x_j] is the analytic tail_to_tail Jacobian (geometry/pose.h,
/// the Jacobian of RelativePose6Model) linearised at the file's vertex estimates (not at the
/// edge measurement); P is options.prior_information on vertex index 0.
/// Throws std::domain_error (from pose.h) if a vertex pitch is within 0.5 deg of +-90 deg.
InformationMatrix assemble_information(const PoseGraph& graph, const AssemblyOptions& options = {});

/// The same matrix as assemble_information(), as a compressed column-major Eigen matrix with
/// both triangles stored (scalar row/col 6a+k is element k of vertex index a). Same throws.
Eigen::SparseMatrix<double> assemble_information_sparse(const PoseGraph& graph,
                                                        const AssemblyOptions& options = {});

}  // namespace nav::core
