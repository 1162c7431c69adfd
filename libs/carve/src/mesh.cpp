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

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
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
// Cut files: a binary STL says how many triangles it holds (84 + 50 N bytes): a file of another size is cut
// or corrupt, and CGAL would read what is there (an open mesh at best) or trust the count.
void check_mesh_size(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".off") {
    // OFF: "OFF" then "V F E"; every vertex takes at least 6 characters ("0 0 0\n"), every face
    // at least 8 ("3 0 1 2\n"): fewer bytes than that is a cut file (and no count is trusted).
    std::ifstream in(path);
    std::string word;
    in >> word;
    if (word.size() < 3 || word.compare(word.size() - 3, 3, "OFF") != 0) return;  // CGAL says why
    auto next_number = [&](double& v) {
      std::string tok;
      while (in >> tok) {
        if (tok[0] == '#') {
          std::getline(in, tok);
          continue;
        }
        try {
          v = std::stod(tok);
          return true;
        } catch (const std::exception&) {
          return false;
        }
      }
      return false;
    };
    double nv = 0, nf = 0;
    if (!next_number(nv) || !next_number(nf)) return;
    std::error_code ec;
    const double size = double(std::filesystem::file_size(path, ec));
    if (!ec && (nv < 0 || nf < 0 || 6 * nv + 8 * nf > size))
      throw InputError(path, "OFF header", std::to_string((long long)nv) + " vertices, " + std::to_string((long long)nf) + " faces",
                       "needs at least " + std::to_string((long long)(6 * nv + 8 * nf)) + " bytes; the file has " +
                           std::to_string((long long)size) + ": truncated or corrupt");
    return;
  }
  if (ext != ".stl") return;
  std::ifstream in(path, std::ios::binary);
  char head[84] = {};
  in.read(head, 84);
  const std::streamsize got = in.gcount();
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return;  // the reader says why
  bool ascii = got >= 5 && std::string(head, 5) == "solid";
  if (got < 84) {
    if (!ascii) throw InputError(path, "", std::to_string(size) + " bytes", "too short for an STL file (a binary STL has an 84-byte header)");
    return;
  }
  uint32_t n = 0;
  std::memcpy(&n, head + 80, 4);
  const std::uint64_t want = 84 + 50 * std::uint64_t(n);
  if (want == size) return;  // a consistent binary STL (even if its header starts with "solid")
  if (ascii) {
    // ASCII STL: it must end with "endsolid" (a cut file does not).
    std::ifstream tail(path, std::ios::binary);
    const std::uint64_t k = std::min<std::uint64_t>(size, 256);
    tail.seekg(std::streamoff(size - k));
    std::string t(k, '\0');
    tail.read(t.data(), std::streamsize(k));
    if (t.find("endsolid") == std::string::npos)
      throw InputError(path, "endsolid", "missing", "the ASCII STL file does not end with 'endsolid': it is truncated");
    return;
  }
  throw InputError(path, "triangle count", std::to_string(n),
                   "a binary STL of " + std::to_string(n) + " triangles has " + std::to_string(want) +
                       " bytes; the file has " + std::to_string(size) + ": truncated or corrupt");
}
}  // namespace

std::unique_ptr<Macropores> load_mesh(const std::string& path, double unit) {
  if (!(unit > 0)) throw InputError(path, "--image-unit", value_text(unit), "must be > 0");
  {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw InputError(path, "", "", "is a folder, not a mesh file");
    if (!std::filesystem::exists(path, ec)) throw InputError(path, "", "", "cannot open: no such file");
  }
  check_mesh_size(path);
  Mesh mesh;
  bool ok = false;
  try {
    ok = CGAL::IO::read_polygon_mesh(path, mesh);
  } catch (const std::exception& e) {
    throw InputError(path, "", "", std::string("cannot read the mesh: ") + e.what());
  }
  if (!ok || mesh.number_of_faces() == 0)
    throw InputError(path, "", "", "cannot read a polygon mesh (STL, OFF, PLY or OBJ; empty or malformed)");
  for (auto v : mesh.vertices()) {
    const Point& q = mesh.point(v);
    if (!std::isfinite(q.x()) || !std::isfinite(q.y()) || !std::isfinite(q.z())) {
      std::ostringstream t;
      t << q.x() << " " << q.y() << " " << q.z();
      throw InputError(path, "vertex " + std::to_string(std::size_t(v)), t.str(), "vertex coordinates must be finite");
    }
  }
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
