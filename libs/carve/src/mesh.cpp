// Closed surface meshes (STL, OFF, PLY, OBJ) through CGAL: read, check closedness, inside test by
// ray parity against an AABB tree (Side_of_triangle_mesh), unsigned distance to the same tree.
#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <cmath>
#include <sstream>

#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::carve {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
namespace PMP = CGAL::Polygon_mesh_processing;

class ClosedMesh final : public Macropores {
 public:
  ClosedMesh(Mesh mesh, double unit, std::string file) : mesh_(std::move(mesh)), unit_(unit), file_(std::move(file)) {
    tree_ = std::make_unique<Tree>(faces(mesh_).first, faces(mesh_).second, mesh_);
    tree_->build();
    tree_->accelerate_distance_queries();
    (void)tree_->squared_distance(Point(0, 0, 0));  // builds the search tree now, before threads share it
    const auto bb = tree_->bbox();
    box_.lo = Vec3{bb.xmin(), bb.ymin(), bb.zmin()} * unit_;
    box_.hi = Vec3{bb.xmax(), bb.ymax(), bb.zmax()} * unit_;
    double len = 0;
    for (auto e : edges(mesh_)) len += CGAL::to_double(PMP::edge_length(halfedge(e, mesh_), mesh_));
    edge_ = unit_ * len / double(std::max<std::size_t>(1, mesh_.number_of_edges()));
  }
  double distance(const Vec3& p) const override {
    const Point q(p.x / unit_, p.y / unit_, p.z / unit_);
    const CGAL::Side_of_triangle_mesh<Mesh, K, CGAL::Default, Tree> side(*tree_);
    const double d = std::sqrt(CGAL::to_double(tree_->squared_distance(q))) * unit_;
    return side(q) == CGAL::ON_BOUNDED_SIDE ? -d : d;
  }
  Box bounds() const override { return box_; }
  double resolution() const override { return edge_; }
  std::string describe() const override {
    return "closed mesh " + file_ + " (" + std::to_string(mesh_.number_of_faces()) + " triangles)";
  }

 private:
  Mesh mesh_;
  double unit_;
  std::string file_;
  std::unique_ptr<Tree> tree_;
  Box box_;
  double edge_ = 0;
};
}  // namespace

std::unique_ptr<Macropores> load_mesh(const std::string& path, double unit) {
  if (!(unit > 0)) throw InputError(path, "--image-unit", std::to_string(unit), "must be > 0");
  Mesh mesh;
  bool ok = false;
  try {
    ok = CGAL::IO::read_polygon_mesh(path, mesh);
  } catch (const std::exception& e) {
    throw InputError(path, "", "", std::string("cannot read the mesh: ") + e.what());
  }
  if (!ok || mesh.number_of_faces() == 0)
    throw InputError(path, "", "", "cannot read a polygon mesh (STL, OFF, PLY or OBJ; empty or malformed)");
  if (!CGAL::is_triangle_mesh(mesh)) PMP::triangulate_faces(mesh);
  if (!CGAL::is_closed(mesh)) {
    std::size_t border = 0;
    for (auto h : halfedges(mesh))
      if (mesh.is_border(h)) ++border;
    throw InputError(path, "mesh", std::to_string(border) + " border edges",
                     "the mesh is open (not watertight): an inside cannot be defined");
  }
  const double vol = std::abs(CGAL::to_double(PMP::volume(mesh)));
  if (!(vol > 0)) throw InputError(path, "mesh", "volume 0", "the closed mesh encloses no volume");
  return std::make_unique<ClosedMesh>(std::move(mesh), unit, path);
}

}  // namespace tomodem::carve
