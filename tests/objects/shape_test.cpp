// Signed distances of the object shapes: exact values where the distance is known, unit
// gradients for the exact ones, gradients against finite differences of φ everywhere, and
// a closed mesh's distance grid against the analytic shape it was made from.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>

#include "knit/io/obj.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/objects/object.hpp"
#include "knit/objects/shape.hpp"
#include "knit/scene/scene_objects.hpp"

namespace knit {
namespace {

using Eigen::Vector3d;

Vector3d fd_grad(const Shape& s, const Vector3d& x, double h = 1e-6) {
  Vector3d g;
  for (int k = 0; k < 3; ++k) {
    Vector3d a = x, b = x;
    a[k] += h;
    b[k] -= h;
    g[k] = (s.distance(a, nullptr) - s.distance(b, nullptr)) / (2 * h);
  }
  return g;
}

std::vector<std::pair<std::string, ShapePtr>> all_analytic() {
  const Vector3d c(0.3, -0.2, 0.5);
  return {
      {"plane", make_plane(c, Vector3d(1, 2, 2))},
      {"sphere", make_sphere(c, 2)},
      {"box", make_box(c, Vector3d(1, 2, 0.5))},
      {"capsule", make_capsule(c, c + Vector3d(2, 1, -1), 0.7)},
      {"cylinder", make_cylinder(c, c + Vector3d(0.5, 3, 1), 1.2)},
      {"ellipsoid", make_ellipsoid(c, Vector3d(2, 1, 1.5))},
      {"union",
       make_union({make_sphere(c, 1), make_box(c + Vector3d(1.5, 0, 0), Vector3d(1, 1, 1))})},
      {"smooth_union", make_union({make_sphere(c, 1),
                                   make_capsule(c + Vector3d(1, 0, 0), c + Vector3d(3, 0, 1), 0.6)},
                                  0.8)},
  };
}

TEST(Shapes, KnownDistances) {
  EXPECT_DOUBLE_EQ(
      make_plane(Vector3d::Zero(), Vector3d(0, 0, 2))->distance(Vector3d(5, 1, 3), nullptr), 3);
  EXPECT_DOUBLE_EQ(make_sphere(Vector3d(1, 0, 0), 2)->distance(Vector3d(1, 0, 5), nullptr), 3);
  const ShapePtr box = make_box(Vector3d::Zero(), Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(box->distance(Vector3d(4, 0, 0), nullptr), 3);       // face
  EXPECT_DOUBLE_EQ(box->distance(Vector3d(4, 6, 0), nullptr), 5);       // edge: 3-4-5
  EXPECT_DOUBLE_EQ(box->distance(Vector3d(0.5, 0, 0), nullptr), -0.5);  // inside
  const ShapePtr cap = make_capsule(Vector3d::Zero(), Vector3d(0, 0, 4), 1);
  EXPECT_DOUBLE_EQ(cap->distance(Vector3d(3, 0, 2), nullptr), 2);
  EXPECT_DOUBLE_EQ(cap->distance(Vector3d(0, 0, 7), nullptr), 2);  // beyond the end cap
  const ShapePtr cyl = make_cylinder(Vector3d::Zero(), Vector3d(0, 0, 4), 1);
  EXPECT_DOUBLE_EQ(cyl->distance(Vector3d(0.2, 0, 7), nullptr), 3);  // above the flat cap
  EXPECT_DOUBLE_EQ(cyl->distance(Vector3d(4, 0, 8), nullptr), 5);    // past the rim: 3-4-5
  EXPECT_DOUBLE_EQ(cyl->distance(Vector3d(0, 0.5, 2), nullptr), -0.5);
  // an ellipsoid with equal semi-axes is the sphere, exactly
  const ShapePtr ell = make_ellipsoid(Vector3d::Zero(), Vector3d(2, 2, 2));
  EXPECT_NEAR(ell->distance(Vector3d(1, 2, 3), nullptr), std::sqrt(14.0) - 2, 1e-12);
  // and a stretched one is zero on its surface
  const ShapePtr e2 = make_ellipsoid(Vector3d::Zero(), Vector3d(3, 1, 2));
  EXPECT_NEAR(e2->distance(Vector3d(3 * std::cos(0.4), std::sin(0.4), 0), nullptr), 0, 1e-12);
  EXPECT_NEAR(e2->distance(Vector3d(4, 0, 0), nullptr), 1, 1e-12);  // on an axis: exact
}

TEST(Shapes, GradientsMatchFiniteDifferencesAndExactOnesHaveUnitLength) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5, 5);
  for (const auto& [name, shape] : all_analytic()) {
    int checked = 0;
    for (int trial = 0; trial < 400; ++trial) {
      const Vector3d x(u(rng), u(rng), u(rng));
      Vector3d g;
      shape->distance(x, &g);
      const Vector3d fd = fd_grad(*shape, x);
      // skip the creases where φ is not differentiable (the medial axis inside a box, the
      // seam of a union): there the one-sided slopes differ and the central difference
      // lies between them
      const Vector3d fd_wide = fd_grad(*shape, x, 1e-4);
      if ((fd - fd_wide).norm() > 1e-4) continue;
      ++checked;
      EXPECT_NEAR((g - fd).norm(), 0, 1e-6) << name << " at " << x.transpose();
      if (name != "ellipsoid" && name != "smooth_union")
        EXPECT_NEAR(g.norm(), 1, 1e-9) << name << " at " << x.transpose();
    }
    EXPECT_GT(checked, 300) << name;
  }
}

TEST(Shapes, SmoothUnionFillsTheCreaseAndEqualsTheUnionAwayFromIt) {
  const ShapePtr a = make_sphere(Vector3d(-1, 0, 0), 1.2), b = make_sphere(Vector3d(1, 0, 0), 1.2);
  const ShapePtr hard = make_union({a, b}), soft = make_union({a, b}, 0.5);
  // in the crease between the two balls the blend lies inside the hard union's surface
  EXPECT_LT(soft->distance(Vector3d(0, 0.9, 0), nullptr),
            hard->distance(Vector3d(0, 0.9, 0), nullptr) - 0.05);
  // never outside the union, and the same where one member is nearer by more than k
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-4, 4);
  for (int k = 0; k < 200; ++k) {
    const Vector3d x(u(rng), u(rng), u(rng));
    const double da = a->distance(x, nullptr), db = b->distance(x, nullptr);
    EXPECT_LE(soft->distance(x, nullptr), hard->distance(x, nullptr) + 1e-12);
    if (std::abs(da - db) >= 0.5) EXPECT_DOUBLE_EQ(soft->distance(x, nullptr), std::min(da, db));
  }
}

TEST(Shapes, BadShapesAreRefused) {
  EXPECT_THROW(make_sphere(Vector3d::Zero(), -1), std::invalid_argument);
  EXPECT_THROW(make_plane(Vector3d::Zero(), Vector3d::Zero()), std::invalid_argument);
  EXPECT_THROW(make_cylinder(Vector3d::Zero(), Vector3d::Zero(), 1), std::invalid_argument);
  EXPECT_THROW(make_box(Vector3d::Zero(), Vector3d(1, 0, 1)), std::invalid_argument);
  EXPECT_THROW(make_union({}), std::invalid_argument);
}

// a moving object: φ follows the keyframed pose and the velocity field is the rigid one
TEST(Objects, FrameFollowsKeyframesAndGivesTheRigidVelocity) {
  SceneObject o;
  o.shape = make_box(Vector3d::Zero(), Vector3d(1, 1, 1));
  o.position = Vector3d(0, 0, 2);
  Keyframe a, b;
  a.time = 0;
  b.time = 2;
  b.translation = Vector3d(4, 0, 0);
  b.rotation = Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ());
  o.keyframes = {a, b};
  const ObjectFrame f(o, 1.0);  // halfway: at (2, 0, 2), turned 45°
  EXPECT_NEAR(f.origin().x(), 2, 1e-12);
  EXPECT_NEAR(f.distance(Vector3d(2, 0, 2), nullptr), -1, 1e-12);
  EXPECT_NEAR(f.distance(Vector3d(2 + std::sqrt(2.0), 0, 2), nullptr), 0, 1e-12);  // a corner
  // velocity: Ṫ = (2, 0, 0) cm/s plus ω = π/4 rad/s about z
  const Vector3d u = f.velocity(Vector3d(2, 1, 2));
  EXPECT_NEAR(u.x(), 2 - M_PI / 4, 1e-12);
  EXPECT_NEAR(u.y(), 0, 1e-12);
  // against the pose's finite difference
  const double dt = 1e-6;
  const ObjectFrame f0(o, 1.0 - dt), f1(o, 1.0 + dt);
  const Vector3d local(0.3, 0.4, -0.2);
  const Vector3d fd = (f1.to_world(local) - f0.to_world(local)) / (2 * dt);
  EXPECT_NEAR((f.velocity(f.to_world(local)) - fd).norm(), 0, 1e-6);
  // held before the first keyframe and after the last
  EXPECT_EQ(ObjectFrame(o, 5.0).velocity(Vector3d::Zero()), Vector3d::Zero());
}

// a closed icosphere-like mesh (a subdivided octahedron pushed onto the sphere)
TriangleMesh sphere_mesh(double radius, int subdivisions) {
  TriangleMesh m;
  m.vertices = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                 {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.vertices.push_back((m.vertices[a] + m.vertices[b]).normalized());
      return mid[key] = static_cast<int>(m.vertices.size()) - 1;
    };
    std::vector<Eigen::Vector3i> next;
    for (const Eigen::Vector3i& t : m.triangles) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.insert(next.end(), {{t[0], ab, ca}, {ab, t[1], bc}, {ca, bc, t[2]}, {ab, bc, ca}});
    }
    m.triangles = next;
  }
  for (Vector3d& v : m.vertices) v *= radius;
  return m;
}

double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (const Eigen::Vector3i& t : m.triangles)
    v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6;
  return v;
}

TEST(MeshShape, DistanceGridOfAClosedMeshMatchesTheShape) {
  const TriangleMesh mesh = sphere_mesh(3, 5);  // 8192 triangles: facets deviate < 1e-3 cm
  EXPECT_EQ(open_edges(mesh), 0);
  MeshGridOptions o;
  o.voxel_size = 0.05;
  const ShapePtr s = make_mesh_shape(mesh, o, "sphere");
  const ShapePtr exact = make_sphere(Vector3d::Zero(), 3);
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  std::uniform_real_distribution<double> depth(-0.5, 0.5);
  for (int k = 0; k < 300; ++k) {
    const Vector3d dir = Vector3d(n(rng), n(rng), n(rng)).normalized();
    const Vector3d x = (3 + depth(rng)) * dir;
    Vector3d g;
    const double phi = s->distance(x, &g);
    EXPECT_NEAR(phi, exact->distance(x, nullptr), 0.01) << x.transpose();
    EXPECT_GT(g.dot(dir), 0.98) << "gradient points outward, " << x.transpose();
    // the gradient is the exact gradient of the interpolant
    const Vector3d fd = fd_grad(*s, x, 1e-7);
    EXPECT_NEAR((g - fd).norm(), 0, 1e-4 * std::max(1.0, g.norm()));
  }
  // far outside: at least the band
  EXPECT_GE(s->distance(Vector3d(20, 0, 0), nullptr), 0.5);
}

TEST(MeshShape, BadMeshesAreRefusedWithTheirReason) {
  const auto dir = std::filesystem::temp_directory_path() / "knit_mesh_test";
  std::filesystem::create_directories(dir);
  const std::string none = (dir / "none.obj").string(), open = (dir / "open.obj").string(),
                    bad = (dir / "bad.obj").string();
  std::ofstream(none) << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  std::ofstream(open) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n";
  std::ofstream(bad) << "v 0 0 0\nf 1 2 3\n";
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { read_obj_mesh(none); }).find("no faces"), std::string::npos);
  EXPECT_NE(message([&] { read_obj_mesh(bad); }).find("bad.obj: line 2"), std::string::npos);
  EXPECT_NE(message([&] { read_obj_mesh((dir / "missing.obj").string()); }).find("missing.obj"),
            std::string::npos);
  const TriangleMesh m = read_obj_mesh(open);
  EXPECT_EQ(open_edges(m), 3);
  EXPECT_NE(message([&] { make_mesh_shape(m, {}, "open.obj"); }).find("not closed"),
            std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(MeshShape, SurfacesOfShapesAreClosedOutwardAndOnTheSurface) {
  const ShapePtr s = make_sphere(Vector3d(1, 0, 0), 2);
  const TriangleMesh m =
      surface_mesh(*s, Eigen::AlignedBox3d(Vector3d::Constant(-10), Vector3d::Constant(10)), 0.1);
  ASSERT_GT(m.triangles.size(), 100u);
  EXPECT_EQ(open_edges(m), 0);
  EXPECT_NEAR(signed_volume(m), 4.0 / 3 * M_PI * 8, 0.02 * 4.0 / 3 * M_PI * 8);  // outward
  for (const Vector3d& v : m.vertices) EXPECT_NEAR(s->distance(v, nullptr), 0, 0.01);
  // a plane within a region: its top face is the plane
  const ShapePtr p = make_plane(Vector3d::Zero(), Vector3d::UnitZ());
  const TriangleMesh pm =
      surface_mesh(*p, Eigen::AlignedBox3d(Vector3d(-5, -5, -1), Vector3d(5, 5, 1)), 0.25);
  ASSERT_GT(pm.triangles.size(), 10u);
  double top = -1e9;
  for (const Vector3d& v : pm.vertices) top = std::max(top, v.z());
  EXPECT_NEAR(top, 0, 1e-6);
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

// The leg warmer's foot ships twice: as a smooth union (examples/leg_warmer.json) and as
// the OBJ mesh written from it (examples/meshes/foot.obj, used by leg_warmer_mesh.json).
// The mesh path must give the same solid: closed, and its distance grid within a fraction
// of the mesh's 0.4 cm sampling of the union's φ near the surface.
TEST(MeshShape, TheShippedFootMeshIsTheFootShape) {
  const auto shapes = load_scene_objects(std::string(KNIT_EXAMPLES) + "/leg_warmer.json");
  const auto meshes = load_scene_objects(std::string(KNIT_EXAMPLES) + "/leg_warmer_mesh.json");
  ASSERT_EQ(shapes.size(), 1u);
  ASSERT_EQ(meshes.size(), 1u);
  EXPECT_EQ(shapes[0]->shape->kind(), "smooth_union");
  EXPECT_EQ(meshes[0]->shape->kind(), "mesh");
  const TriangleMesh foot = read_obj_mesh(std::string(KNIT_EXAMPLES) + "/meshes/foot.obj");
  EXPECT_EQ(open_edges(foot), 0);
  std::mt19937 rng(5);
  double worst = 0;
  int near_surface = 0;
  for (const Eigen::Vector3d& v : foot.vertices) {
    if (rng() % 20 != 0) continue;  // 1 vertex in 20
    worst = std::max(worst, std::abs(shapes[0]->shape->distance(v, nullptr)));
    // just off the surface, where the yarn meets it
    Vector3d g;
    shapes[0]->shape->distance(v, &g);
    const Vector3d x = v + 0.1 * g.normalized();
    EXPECT_NEAR(meshes[0]->shape->distance(x, nullptr), shapes[0]->shape->distance(x, nullptr),
                0.05)
        << x.transpose();
    ++near_surface;
  }
  EXPECT_GT(near_surface, 300);
  EXPECT_LT(worst, 0.05) << "the mesh's vertices lie on the union's surface";
}

}  // namespace
}  // namespace knit
