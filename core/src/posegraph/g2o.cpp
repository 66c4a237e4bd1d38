// g2o reader (VERTEX_SE3:QUAT / EDGE_SE3:QUAT, and VERTEX_SE2 / EDGE_SE2 lifted to 3-D) and
// pose-graph information assembly (posegraph/g2o.h). Conversions: see the header comment.

#include "nav/core/posegraph/g2o.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"

namespace nav::core {

G2oError::G2oError(const std::string& source, int line, const std::string& reason)
    : std::runtime_error(source + ":" + std::to_string(line) + ": " + reason), line_(line) {}

namespace {

constexpr int kVertexFields = 9;  // tag id x y z qx qy qz qw
constexpr int kEdgeFields = 31;   // tag i j x y z qx qy qz qw + 21 information entries
constexpr int kPlanarVertexFields = 5;  // tag id x y theta
constexpr int kPlanarEdgeFields = 12;   // tag i j dx dy dtheta + 6 information entries

struct LineContext {
  const std::string& source;
  int line;
  [[noreturn]] void fail(const std::string& reason) const { throw G2oError(source, line, reason); }
};

std::vector<std::string> split_fields(const std::string& text) {
  std::istringstream ss(text);
  std::vector<std::string> fields;
  std::string field;
  while (ss >> field) fields.push_back(field);
  return fields;
}

double parse_double(const std::string& field, const char* what, const LineContext& ctx) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(field.c_str(), &end);
  if (end == field.c_str() || *end != '\0') {
    ctx.fail(std::string("non-numeric ") + what + " '" + field + "'");
  }
  if (!std::isfinite(v) || errno == ERANGE) {
    ctx.fail(std::string("non-finite ") + what + " '" + field + "'");
  }
  return v;
}

int parse_id(const std::string& field, const LineContext& ctx) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(field.c_str(), &end, 10);
  if (end == field.c_str() || *end != '\0') ctx.fail("non-integer vertex id '" + field + "'");
  if (errno == ERANGE || v < 0 || v > 1'000'000'000) {
    ctx.fail("vertex id '" + field + "' out of range [0, 1e9]");
  }
  return static_cast<int>(v);
}

/// Reads "x y z qx qy qz qw" starting at fields[first]; returns [t; rpy] and the rotation.
Vec6 parse_pose(const std::vector<std::string>& fields, size_t first, const LineContext& ctx) {
  static const char* kNames[7] = {"x", "y", "z", "qx", "qy", "qz", "qw"};
  double v[7];
  for (size_t k = 0; k < 7; ++k) v[k] = parse_double(fields[first + k], kNames[k], ctx);
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    std::ostringstream msg;
    msg << "quaternion norm " << norm << " differs from 1 by more than "
        << kQuaternionNormTolerance;
    ctx.fail(msg.str());
  }
  q.normalize();
  Vec6 pose;
  pose << v[0], v[1], v[2], euler_from_rotation(q.toRotationMatrix());
  return pose;
}

/// Reads the upper triangle of an N x N information matrix, row by row, from fields[first];
/// fails unless it is positive definite.
template <int N>
Eigen::Matrix<double, N, N> parse_information(const std::vector<std::string>& fields, size_t first,
                                              const LineContext& ctx) {
  Eigen::Matrix<double, N, N> information;
  size_t f = first;
  for (int r = 0; r < N; ++r) {
    for (int c = r; c < N; ++c) {
      information(r, c) = information(c, r) = parse_double(fields[f++], "information entry", ctx);
    }
  }
  if (Eigen::LLT<Eigen::Matrix<double, N, N>>(information).info() != Eigen::Success) {
    ctx.fail("information matrix is not positive definite (LLT)");
  }
  return information;
}

/// Reads "x y theta" at fields[first]: the pose [x y 0 0 0 theta] (theta wrapped).
Vec6 parse_planar_pose(const std::vector<std::string>& fields, size_t first,
                       const LineContext& ctx) {
  Vec6 pose = Vec6::Zero();
  pose[0] = parse_double(fields[first], "x", ctx);
  pose[1] = parse_double(fields[first + 1], "y", ctx);
  pose[5] = wrap_angle(parse_double(fields[first + 2], "theta", ctx));
  return pose;
}

/// EdgeSE2's information on [t_err (2); theta_err] as EdgeSE3's on [t_err; qvec_err]
/// (header comment): qvec_z = theta/2 scales the theta row and column by 2; z gets the mean of
/// the x and y entries, qvec_x and qvec_y the qvec_z entry.
Mat6 lifted_planar_information(const std::vector<std::string>& fields, size_t first,
                               const LineContext& ctx) {
  const Mat3 planar = parse_information<3>(fields, first, ctx);
  constexpr int kIn[3] = {0, 1, 5};  // x, y, qvec_z in EdgeSE3's error
  constexpr double kScale[3] = {1.0, 1.0, 2.0};
  Mat6 lifted = Mat6::Zero();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) lifted(kIn[r], kIn[c]) = kScale[r] * kScale[c] * planar(r, c);
  }
  lifted(2, 2) = 0.5 * (planar(0, 0) + planar(1, 1));
  lifted(3, 3) = lifted(4, 4) = lifted(5, 5);
  return lifted;
}

struct RawEdge {
  int from, to, line;
  Vec6 measurement;
  Mat6 information_g2o;
};

}  // namespace

Mat6 g2o_error_jacobian(const Vec6& measurement) {
  Mat6 G = Mat6::Zero();
  G.topLeftCorner<3, 3>() = rotation_from_euler(measurement.tail<3>()).transpose();
  G.bottomRightCorner<3, 3>() = 0.5 * euler_rate_matrix_inverse(measurement.tail<3>());
  return G;
}

namespace {

/// The elements of a file as read, before edges are resolved against vertices.
class RawGraph {
 public:
  /// Parses one non-comment line (fields non-empty).
  void read_line(const std::vector<std::string>& fields, const LineContext& ctx) {
    const std::string& tag = fields[0];
    if (tag == "VERTEX_SE3:QUAT" || tag == "VERTEX_SE2") {
      const bool planar = tag == "VERTEX_SE2";
      expect_fields(fields, planar ? kPlanarVertexFields : kVertexFields, ctx);
      note_kind(planar, ctx);
      const int id = parse_id(fields[1], ctx);
      const Vec6 pose = planar ? parse_planar_pose(fields, 2, ctx) : parse_pose(fields, 2, ctx);
      const auto [it, inserted] = vertices.emplace(id, std::make_pair(pose, ctx.line));
      if (!inserted) {
        ctx.fail("duplicate vertex " + std::to_string(id) + " (first defined on line " +
                 std::to_string(it->second.second) + ")");
      }
    } else if (tag == "EDGE_SE3:QUAT" || tag == "EDGE_SE2") {
      const bool planar = tag == "EDGE_SE2";
      expect_fields(fields, planar ? kPlanarEdgeFields : kEdgeFields, ctx);
      note_kind(planar, ctx);
      RawEdge e;
      e.from = parse_id(fields[1], ctx);
      e.to = parse_id(fields[2], ctx);
      if (e.from == e.to) ctx.fail("edge from vertex " + std::to_string(e.from) + " to itself");
      e.line = ctx.line;
      e.measurement = planar ? parse_planar_pose(fields, 3, ctx) : parse_pose(fields, 3, ctx);
      e.information_g2o = planar ? lifted_planar_information(fields, 6, ctx)
                                 : parse_information<6>(fields, 10, ctx);
      edges.push_back(e);
    } else if (tag == "FIX") {
      if (fields.size() < 2) ctx.fail("FIX names no vertex");
      for (size_t k = 1; k < fields.size(); ++k) parse_id(fields[k], ctx);  // gauge: see header
    } else {
      ctx.fail("unknown tag '" + tag +
               "' (expected VERTEX_SE3:QUAT, EDGE_SE3:QUAT, VERTEX_SE2, EDGE_SE2 or FIX)");
    }
  }

  std::map<int, std::pair<Vec6, int>> vertices;  // id -> (pose, line)
  std::vector<RawEdge> edges;
  int planar_line = 0, spatial_line = 0;  // first line of each kind, 0 if none

 private:
  static void expect_fields(const std::vector<std::string>& fields, int expected,
                            const LineContext& ctx) {
    if (fields.size() != static_cast<size_t>(expected)) {
      ctx.fail(fields[0] + " has " + std::to_string(fields.size()) + " fields, expected " +
               std::to_string(expected));
    }
  }
  void note_kind(bool planar, const LineContext& ctx) {
    int& first = planar ? planar_line : spatial_line;
    if (first == 0) first = ctx.line;
    const int other = planar ? spatial_line : planar_line;
    if (other != 0) {
      ctx.fail(std::string(planar ? "planar (SE2)" : "3-D (SE3)") +
               " element in a file whose line " + std::to_string(other) + " is " +
               (planar ? "3-D (SE3)" : "planar (SE2)"));
    }
  }
};

}  // namespace

PoseGraph read_g2o(std::istream& in, const std::string& source_name) {
  RawGraph raw;
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    const std::vector<std::string> fields = split_fields(text);
    if (fields.empty() || fields[0][0] == '#') continue;
    raw.read_line(fields, LineContext{source_name, line_no});
  }
  if (in.bad()) throw G2oError(source_name, line_no, "read error");

  PoseGraph graph;
  std::map<int, int> index_of;
  graph.planar = raw.planar_line != 0;
  graph.vertices.reserve(raw.vertices.size());
  for (const auto& [id, pose_line] : raw.vertices) {
    index_of[id] = static_cast<int>(graph.vertices.size());
    graph.vertices.push_back(G2oVertex{id, pose_line.first});
  }
  graph.edges.reserve(raw.edges.size());
  for (const RawEdge& edge : raw.edges) {
    const LineContext ctx{source_name, edge.line};
    const auto from = index_of.find(edge.from);
    const auto to = index_of.find(edge.to);
    if (from == index_of.end()) ctx.fail("edge from unknown vertex " + std::to_string(edge.from));
    if (to == index_of.end()) ctx.fail("edge to unknown vertex " + std::to_string(edge.to));
    G2oEdge e;
    e.from = edge.from;
    e.to = edge.to;
    e.from_index = from->second;
    e.to_index = to->second;
    e.measurement = edge.measurement;
    e.information_g2o = edge.information_g2o;
    if (pitch_is_singular(edge.measurement[4])) {
      ctx.fail("edge measurement pitch within 0.5 deg of +-90 deg: Euler information undefined");
    }
    const Mat6 G = g2o_error_jacobian(edge.measurement);
    e.information = G.transpose() * edge.information_g2o * G;
    e.information = 0.5 * (e.information + e.information.transpose()).eval();
    e.line = edge.line;
    graph.edges.push_back(e);
  }
  return graph;
}

PoseGraph read_g2o(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw G2oError(path, 0, "cannot open file");
  return read_g2o(file, path);
}

namespace {

/// Calls add(a, b, block) for every 6x6 block contribution (a, b vertex indices, both orders
/// for a != b) of the prior and of every edge.
template <typename Add>
void for_each_information_block(const PoseGraph& graph, const AssemblyOptions& options, Add add) {
  if (graph.vertices.empty()) return;
  add(0, 0, options.prior_information);
  for (const G2oEdge& e : graph.edges) {
    Mat6x12 H;
    tail_to_tail(graph.vertices[static_cast<size_t>(e.from_index)].pose,
                 graph.vertices[static_cast<size_t>(e.to_index)].pose, &H);
    const Mat6 Hi = H.leftCols<6>();
    const Mat6 Hj = H.rightCols<6>();
    const Mat6 OHi = e.information * Hi;
    const Mat6 OHj = e.information * Hj;
    add(e.from_index, e.from_index, Mat6(Hi.transpose() * OHi));
    add(e.to_index, e.to_index, Mat6(Hj.transpose() * OHj));
    const Mat6 ij = Hi.transpose() * OHj;
    add(e.from_index, e.to_index, ij);
    add(e.to_index, e.from_index, Mat6(ij.transpose()));
  }
}

}  // namespace

InformationMatrix assemble_information(const PoseGraph& graph, const AssemblyOptions& options) {
  InformationMatrix Lambda(kPoseDim);
  for (size_t k = 0; k < graph.vertices.size(); ++k) Lambda.add_block();
  for_each_information_block(graph, options, [&](int a, int b, const Mat6& m) {
    if (a <= b) Lambda.add_to_block(a, b, m);  // add_to_block mirrors (b, a) itself
  });
  return Lambda;
}

Eigen::SparseMatrix<double> assemble_information_sparse(const PoseGraph& graph,
                                                        const AssemblyOptions& options) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve((graph.edges.size() * 4 + 1) * 36);
  for_each_information_block(graph, options, [&](int a, int b, const Mat6& m) {
    for (int c = 0; c < 6; ++c) {
      for (int r = 0; r < 6; ++r) triplets.emplace_back(6 * a + r, 6 * b + c, m(r, c));
    }
  });
  const Eigen::Index n = static_cast<Eigen::Index>(graph.vertices.size()) * kPoseDim;
  Eigen::SparseMatrix<double> Lambda(n, n);
  Lambda.setFromTriplets(triplets.begin(), triplets.end());
  return Lambda;
}

}  // namespace nav::core
