// knitsim mesh SCENE.json --object NAME --out FILE.obj [--time T] [--voxel CM]: writes an
// object's surface as a closed triangle mesh (e.g. to ship a shape as a mesh, or to look at
// it in a modelling tool).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "common.hpp"
#include "knit/io/obj.hpp"
#include "knit/objects/mesh_shape.hpp"
#include "knit/scene/scene_objects.hpp"

namespace knitsim {

void register_mesh(CLI::App& app) {
  struct Opts {
    std::string scene, object, out;
    double time = 0, voxel = 0;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd =
      app.add_subcommand("mesh", "write a scene object's surface as a triangle mesh (OBJ)");
  add_required_path(cmd, "scene", o->scene, "scene file (JSON)")->check(existing_file());
  add_text(cmd, "--object", o->object, "the object's name in the scene", "name", "none (required)")
      ->required();
  add_out_option(cmd, o->out, "output .obj file");
  add_number(cmd, "--time", o->time, "where a moving object is at this time", "s",
             closed(0, knit::MAX_DURATION));
  add_number(cmd, "--voxel", o->voxel, "the sampling grid's spacing", "cm", closed(1e-3, 100),
             "the object's size / 160");
  cmd->callback([o]() {
    if (std::filesystem::path(o->out).extension() != ".obj")
      throw std::invalid_argument("--out " + o->out +
                                  ": knitsim writes OBJ meshes; give a .obj name");
    const auto objects = knit::load_scene_objects(o->scene);
    for (const auto& obj : objects) {
      if (obj->name != o->object) continue;
      Eigen::AlignedBox3d box = obj->shape->bounds();
      if (!box.diagonal().allFinite())
        throw std::invalid_argument("--object " + o->object + ": a " +
                                    std::string(obj->shape->kind()) +
                                    " is unbounded and has no closed surface to write");
      const knit::ObjectFrame f(*obj, o->time);
      Eigen::AlignedBox3d world;
      for (int c = 0; c < 8; ++c)
        world.extend(f.to_world(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c))));
      world.min().array() -= 0.05 * world.diagonal().norm();
      world.max().array() += 0.05 * world.diagonal().norm();
      const knit::TriangleMesh m = knit::object_surface(*obj, o->time, world, o->voxel);
      knit::write_obj_mesh(m, o->out);
      std::cout << "wrote " << o->out << " (" << m.vertices.size() << " vertices, "
                << m.triangles.size() << " triangles, " << knit::open_edges(m) << " open edges)\n";
      return;
    }
    std::string names;
    for (const auto& obj : objects) names += (names.empty() ? "" : ", ") + obj->name;
    throw std::invalid_argument("--object " + o->object + ": " + o->scene +
                                " has no such object (" +
                                (names.empty() ? "it has none" : "it has " + names) + ")");
  });
}

const bool mesh_added = add_command(70, register_mesh);

}  // namespace knitsim
