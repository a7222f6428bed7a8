#include "knit/sheet/sheet.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "knit/sheet/bw_energy.hpp"

namespace knit::sheet {

namespace {

// the Jacobians' block sparsity and every element's slots in it (SheetMesh docs)
void build_assembly_cache(SheetMesh& mesh) {
  const int n = mesh.num_nodes();
  auto hinge_nodes = [](const SheetHinge& h) {
    return std::array<int, 4>{h.opposite[0], h.opposite[1], h.edge[0], h.edge[1]};
  };
  // sorted neighbours of every node (itself included): the nodes it shares an element with
  std::vector<std::vector<int>> nbr(n);
  for (const auto& tri : mesh.triangles)
    for (int a : tri)
      for (int b : tri) nbr[b].push_back(a);
  for (const SheetHinge& h : mesh.hinges)  // adds the opposite–opposite pairs
    for (int a : hinge_nodes(h))
      for (int b : hinge_nodes(h)) nbr[b].push_back(a);
  Eigen::VectorXi sizes(3 * n);
  for (int b = 0; b < n; ++b) {
    std::sort(nbr[b].begin(), nbr[b].end());
    nbr[b].erase(std::unique(nbr[b].begin(), nbr[b].end()), nbr[b].end());
    sizes.segment<3>(3 * b).setConstant(3 * static_cast<int>(nbr[b].size()));
  }
  Eigen::SparseMatrix<double>& p = mesh.jacobian_pattern;
  p.resize(3 * n, 3 * n);
  p.reserve(sizes);
  for (int b = 0; b < n; ++b)
    for (int c = 0; c < 3; ++c)
      for (int a : nbr[b])
        for (int r = 0; r < 3; ++r) p.insert(3 * a + r, 3 * b + c) = 0.0;
  p.makeCompressed();
  // offset of row 3a in column 3b from the column's start
  auto slot = [&](int a, int b) {
    const auto it = std::lower_bound(nbr[b].begin(), nbr[b].end(), a);
    assert(it != nbr[b].end() && *it == a);
    return 3 * static_cast<int>(it - nbr[b].begin());
  };
  mesh.triangle_slots.resize(mesh.triangles.size());
  for (size_t e = 0; e < mesh.triangles.size(); ++e)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        mesh.triangle_slots[e][3 * a + b] = slot(mesh.triangles[e][a], mesh.triangles[e][b]);
  mesh.hinge_slots.resize(mesh.hinges.size());
  for (size_t e = 0; e < mesh.hinges.size(); ++e) {
    const auto nodes = hinge_nodes(mesh.hinges[e]);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) mesh.hinge_slots[e][4 * a + b] = slot(nodes[a], nodes[b]);
  }
}

}  // namespace

Eigen::VectorXd SheetMesh::rest_positions() const {
  return Eigen::Map<const Eigen::VectorXd>(rest.data(), rest.size());
}

void set_density(SheetMesh& mesh, double density) {
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument("sheet density must be positive (g/cm²), got " +
                                std::to_string(density));
  mesh.mass = density * mesh.node_area;
}

SheetMesh make_sheet_mesh(Eigen::Matrix3Xd rest, Eigen::Matrix2Xd uv,
                          std::vector<std::array<int, 3>> triangles, double density) {
  const int n = static_cast<int>(rest.cols());
  if (uv.cols() != n)
    throw std::invalid_argument("sheet mesh: uv has " + std::to_string(uv.cols()) +
                                " columns, expected one per node (" + std::to_string(n) + ")");
  if (triangles.empty()) throw std::invalid_argument("sheet mesh: triangles is empty");
  if (!rest.allFinite() || !uv.allFinite())
    throw std::invalid_argument("sheet mesh: rest positions and uv must be finite");
  SheetMesh mesh;
  mesh.rest = std::move(rest);
  mesh.uv = std::move(uv);
  mesh.triangles = std::move(triangles);
  const int nt = static_cast<int>(mesh.triangles.size());
  mesh.dinv.resize(nt);
  mesh.area.resize(nt);
  mesh.node_area = Eigen::VectorXd::Zero(n);

  // material-space size, for the degeneracy test
  const double extent = (mesh.uv.rowwise().maxCoeff() - mesh.uv.rowwise().minCoeff()).norm();
  for (int t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] < 0 || tri[k] >= n)
        throw std::invalid_argument("sheet mesh: triangle " + std::to_string(t) + " names node " +
                                    std::to_string(tri[k]) + ", out of [0, " + std::to_string(n) +
                                    ")");
    Eigen::Matrix2d d;
    d.col(0) = mesh.uv.col(tri[1]) - mesh.uv.col(tri[0]);
    d.col(1) = mesh.uv.col(tri[2]) - mesh.uv.col(tri[0]);
    const double det = d.determinant();
    if (!(std::abs(det) > 1e-12 * extent * extent))
      throw std::invalid_argument("sheet mesh: triangle " + std::to_string(t) +
                                  " has zero material (u, v) area");
    mesh.dinv[t] = d.inverse();
    mesh.area[t] = 0.5 * std::abs(det);
    for (int k = 0; k < 3; ++k) mesh.node_area[tri[k]] += mesh.area[t] / 3;
  }

  // hinges: edges shared by exactly two triangles
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> edges;  // -> (tri, opposite)
  for (int t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int a = tri[(k + 1) % 3], b = tri[(k + 2) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back({t, tri[k]});
    }
  }
  const Eigen::VectorXd x0 = mesh.rest_positions();
  for (const auto& [e, sides] : edges) {
    if (sides.size() > 2)
      throw std::invalid_argument("sheet mesh: edge (" + std::to_string(e.first) + ", " +
                                  std::to_string(e.second) + ") is shared by " +
                                  std::to_string(sides.size()) + " triangles (non-manifold)");
    if (sides.size() < 2) continue;
    SheetHinge h;
    h.edge = {e.first, e.second};
    h.opposite = {sides[0].second, sides[1].second};
    h.rest_angle = bend_angle(hinge_positions(h, x0));
    h.rest_area_product = bend_area_product(hinge_positions(h, x0));
    if (!(h.rest_area_product > 0))
      throw std::invalid_argument("sheet mesh: a triangle at edge (" + std::to_string(e.first) +
                                  ", " + std::to_string(e.second) + ") has no area");
    mesh.hinges.push_back(h);
  }
  set_density(mesh, density);
  build_assembly_cache(mesh);
  return mesh;
}

SheetMesh make_rectangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& u_axis,
                         const Eigen::Vector3d& v_axis, double width, double height, int nu, int nv,
                         double density) {
  if (!(width > 0) || !std::isfinite(width))
    throw std::invalid_argument("make_rectangle: width must be positive (cm), got " +
                                std::to_string(width));
  if (!(height > 0) || !std::isfinite(height))
    throw std::invalid_argument("make_rectangle: height must be positive (cm), got " +
                                std::to_string(height));
  if (nu < 2)
    throw std::invalid_argument("make_rectangle: nu must be >= 2, got " + std::to_string(nu));
  if (nv < 2)
    throw std::invalid_argument("make_rectangle: nv must be >= 2, got " + std::to_string(nv));
  if (!(density > 0) || !std::isfinite(density))
    throw std::invalid_argument("make_rectangle: density must be positive (g/cm²), got " +
                                std::to_string(density));
  if (!origin.allFinite() || !u_axis.allFinite() || !v_axis.allFinite())
    throw std::invalid_argument("make_rectangle: origin and axes must be finite");
  if (!(u_axis.norm() > 0)) throw std::invalid_argument("make_rectangle: u_axis is zero");
  if (!(v_axis.norm() > 0)) throw std::invalid_argument("make_rectangle: v_axis is zero");
  const Eigen::Vector3d eu = u_axis.normalized();
  if (eu.cross(v_axis.normalized()).norm() < 1e-9)
    throw std::invalid_argument("make_rectangle: u_axis and v_axis are parallel");
  // the v axis made orthogonal to u (Gram–Schmidt), so the rest shape is a true rectangle
  const Eigen::Vector3d ev = (v_axis - v_axis.dot(eu) * eu).normalized();

  Eigen::Matrix3Xd rest(3, nu * nv);
  Eigen::Matrix2Xd uv(2, nu * nv);
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double u = width * i / (nu - 1), v = height * j / (nv - 1);
      rest.col(j * nu + i) = origin + u * eu + v * ev;
      uv.col(j * nu + i) = Eigen::Vector2d(u, v);
    }
  std::vector<std::array<int, 3>> tris;
  tris.reserve(2 * (nu - 1) * (nv - 1));
  for (int j = 0; j + 1 < nv; ++j)
    for (int i = 0; i + 1 < nu; ++i) {
      const int a = j * nu + i, b = a + 1, c = a + nu + 1, d = a + nu;  // counter-clockwise
      if ((i + j) % 2 == 0) {                                           // diagonal a–c
        tris.push_back({a, b, c});
        tris.push_back({a, c, d});
      } else {  // diagonal b–d
        tris.push_back({a, b, d});
        tris.push_back({b, c, d});
      }
    }
  SheetMesh mesh = make_sheet_mesh(std::move(rest), std::move(uv), std::move(tris), density);
  mesh.nu = nu;
  mesh.nv = nv;
  return mesh;
}

int grid_node(const SheetMesh& mesh, int i, int j) {
  if (mesh.nu < 2 || mesh.nv < 2)
    throw std::invalid_argument("grid_node: the mesh is not a make_rectangle grid");
  if (i < 0 || i >= mesh.nu)
    throw std::invalid_argument("grid_node: i = " + std::to_string(i) + " out of [0, " +
                                std::to_string(mesh.nu) + ")");
  if (j < 0 || j >= mesh.nv)
    throw std::invalid_argument("grid_node: j = " + std::to_string(j) + " out of [0, " +
                                std::to_string(mesh.nv) + ")");
  return j * mesh.nu + i;
}

std::vector<int> grid_column(const SheetMesh& mesh, int i) {
  std::vector<int> nodes;
  for (int j = 0; j < mesh.nv; ++j) nodes.push_back(grid_node(mesh, i, j));
  if (nodes.empty()) throw std::invalid_argument("grid_column: the mesh is not a grid");
  return nodes;
}

std::vector<int> grid_row(const SheetMesh& mesh, int j) {
  std::vector<int> nodes;
  for (int i = 0; i < mesh.nu; ++i) nodes.push_back(grid_node(mesh, i, j));
  if (nodes.empty()) throw std::invalid_argument("grid_row: the mesh is not a grid");
  return nodes;
}

}  // namespace knit::sheet
