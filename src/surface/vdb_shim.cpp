/* vdb_shim.cpp - the one C++ file of the engine: OpenVDB behind the C functions of vdb_shim.h.
 *
 * Particles become a level set by OpenVDB's ParticlesToLevelSet (the CSG union of one sphere per
 * particle, Zhu and Bridson 2005's starting point), are smoothed by LevelSetFilter (mean
 * curvature, Gaussian or Laplacian flow, each followed by renormalization to a signed distance)
 * and meshed by volumeToMesh (dual contouring of the zero crossing, Museth 2013 sec. 7). Every
 * entry point catches all exceptions and turns them into a message: none reaches C. */
#include "surface/vdb_shim.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetFilter.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>

struct mpm_vdb_grid {
  openvdb::FloatGrid::Ptr grid;
};

struct mpm_vdb_vector_grid {
  openvdb::Vec3SGrid::Ptr grid;
};

namespace {

void say(char *msg, size_t cap, const char *what, const char *detail) {
  if (msg && cap) std::snprintf(msg, cap, "%s%s%s", what, detail ? ": " : "", detail ? detail : "");
}

/* TBB's workers for the length of one call (0: its default). */
struct thread_limit {
  std::unique_ptr<tbb::global_control> control;
  explicit thread_limit(int threads) {
    if (threads > 0)
      control.reset(
          new tbb::global_control(tbb::global_control::max_allowed_parallelism, (size_t)threads));
  }
};

/* The particle list ParticlesToLevelSet reads (the interface its header documents). */
struct sphere_list {
  using PosType = openvdb::Vec3R;
  const double *xyz, *radius;
  size_t n;
  size_t size() const { return n; }
  void getPos(size_t i, openvdb::Vec3R &p) const { p = openvdb::Vec3R(xyz + 3 * i); }
  void getPosRad(size_t i, openvdb::Vec3R &p, openvdb::Real &r) const {
    p = openvdb::Vec3R(xyz + 3 * i);
    r = radius[i];
  }
};

} // namespace

extern "C" {

int mpm_vdb_available(void) {
  return 1;
}

int mpm_vdb_levelset_from_spheres(const double *xyz, const double *radius, size_t n, double voxel,
                                  double half_width, int threads, mpm_vdb_grid **out, char *msg,
                                  size_t cap) {
  *out = nullptr;
  if (!(voxel > 0) || !(half_width >= 2)) {
    say(msg, cap, "level set: the voxel size must be > 0 and the band at least 2 voxels", nullptr);
    return MPM_VDB_FAIL;
  }
  try {
    openvdb::initialize();
    thread_limit limit(threads);
    openvdb::FloatGrid::Ptr grid = openvdb::createLevelSet<openvdb::FloatGrid>(voxel, half_width);
    grid->setName("surface");
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
    raster.setRmin(0.5);
    sphere_list list{xyz, radius, n};
    raster.rasterizeSpheres(list);
    raster.finalize(true);
    *out = new mpm_vdb_grid{grid};
    return MPM_VDB_OK;
  } catch (const std::exception &e) {
    say(msg, cap, "OpenVDB failed making the level set", e.what());
  } catch (...) {
    say(msg, cap, "OpenVDB failed making the level set", "unknown exception");
  }
  return MPM_VDB_FAIL;
}

int mpm_vdb_smooth(mpm_vdb_grid *g, int passes, mpm_vdb_filter filter, double offset, int threads,
                   char *msg, size_t cap) {
  try {
    thread_limit limit(threads);
    /* A union of spheres is a signed distance only near its surface: deep inside, each voxel
       holds the distance to its nearest sphere, so the whole interior stays in the band (and
       would be filtered at every pass). The band is rebuilt from the zero isosurface (meshed,
       then converted back to an exact narrow band of 3 voxels, what the filters need)
       first. */
    const float half_width = (float)(g->grid->background() / g->grid->voxelSize()[0]);
    openvdb::FloatGrid::Ptr rebuilt = openvdb::tools::levelSetRebuild(*g->grid, 0.0f, half_width);
    rebuilt->setName(g->grid->getName());
    rebuilt->setGridClass(openvdb::GRID_LEVEL_SET);
    g->grid = rebuilt;
    openvdb::tools::LevelSetFilter<openvdb::FloatGrid> f(*g->grid);
    for (int k = 0; k < passes; ++k) {
      if (filter == MPM_VDB_FILTER_GAUSSIAN)
        f.gaussian(1);
      else if (filter == MPM_VDB_FILTER_LAPLACIAN)
        f.laplacian();
      else
        f.meanCurvature();
    }
    if (offset != 0) f.offset((float)offset);
    return MPM_VDB_OK;
  } catch (const std::exception &e) {
    say(msg, cap, "OpenVDB failed smoothing the level set", e.what());
  } catch (...) {
    say(msg, cap, "OpenVDB failed smoothing the level set", "unknown exception");
  }
  return MPM_VDB_FAIL;
}

/* The engine's allocator for the arrays handed to it (the loader sets it: mpm_alloc). */
static void *(*engine_alloc)(size_t) = std::malloc;
static void (*engine_release)(void *) = std::free;

static void set_allocator(void *(*alloc)(size_t), void (*release)(void *)) {
  engine_alloc = alloc;
  engine_release = release;
}

int mpm_vdb_mesh(const mpm_vdb_grid *g, int threads, float **points, size_t *point_count,
                 uint32_t **triangles, size_t *triangle_count, char *msg, size_t cap) {
  *points = nullptr;
  *triangles = nullptr;
  *point_count = *triangle_count = 0;
  try {
    thread_limit limit(threads);
    std::vector<openvdb::Vec3s> pts;
    std::vector<openvdb::Vec3I> tris;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(*g->grid, pts, tris, quads, 0.0, 0.0, true);
    const size_t nt = tris.size() + 2 * quads.size();
    float *p = (float *)engine_alloc((3 * pts.size() + 1) * sizeof(float));
    uint32_t *t = (uint32_t *)engine_alloc((3 * nt + 1) * sizeof(uint32_t));
    if (!p || !t) {
      if (p) engine_release(p);
      if (t) engine_release(t);
      say(msg, cap, "out of memory for the surface mesh", nullptr);
      return MPM_VDB_FAIL;
    }
    for (size_t i = 0; i < pts.size(); ++i)
      for (int d = 0; d < 3; ++d) p[3 * i + d] = pts[i][d];
    /* volumeToMesh winds its polygons clockwise seen from outside a level set (normals into
       the negative region): reversed here, so that normals point out */
    size_t k = 0;
    for (const openvdb::Vec3I &q : tris) {
      t[k++] = q[0], t[k++] = q[2], t[k++] = q[1];
    }
    for (const openvdb::Vec4I &q : quads) { /* split along the diagonal 0-2 */
      t[k++] = q[0], t[k++] = q[2], t[k++] = q[1];
      t[k++] = q[0], t[k++] = q[3], t[k++] = q[2];
    }
    *points = p;
    *triangles = t;
    *point_count = pts.size();
    *triangle_count = nt;
    return MPM_VDB_OK;
  } catch (const std::exception &e) {
    say(msg, cap, "OpenVDB failed meshing the level set", e.what());
  } catch (...) {
    say(msg, cap, "OpenVDB failed meshing the level set", "unknown exception");
  }
  return MPM_VDB_FAIL;
}

uint64_t mpm_vdb_active_voxels(const mpm_vdb_grid *g) {
  return g->grid->activeVoxelCount();
}

int mpm_vdb_velocity_from_particles(const double *xyz, const double *v, const double *mass,
                                    size_t n, double voxel, mpm_vdb_vector_grid **out, char *msg,
                                    size_t cap) {
  *out = nullptr;
  if (!(voxel > 0)) {
    say(msg, cap, "velocity grid: the voxel size must be > 0", nullptr);
    return MPM_VDB_FAIL;
  }
  try {
    openvdb::initialize();
    /* P2G with the trilinear (tent) kernel on the voxel centres: momentum and mass per voxel,
       then the velocity is their ratio (a rigid motion's velocity comes back exactly) */
    openvdb::Vec3DGrid::Ptr momentum = openvdb::Vec3DGrid::create(openvdb::Vec3d(0));
    openvdb::DoubleGrid::Ptr weight = openvdb::DoubleGrid::create(0.0);
    openvdb::Vec3DGrid::Accessor pa = momentum->getAccessor();
    openvdb::DoubleGrid::Accessor wa = weight->getAccessor();
    const double inv = 1 / voxel;
    for (size_t p = 0; p < n; ++p) {
      const double *x = xyz + 3 * p;
      int base[3];
      double f[3];
      for (int d = 0; d < 3; ++d) {
        const double s = x[d] * inv, b = std::floor(s);
        base[d] = (int)b;
        f[d] = s - b;
      }
      const openvdb::Vec3d mv(mass[p] * v[3 * p], mass[p] * v[3 * p + 1], mass[p] * v[3 * p + 2]);
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          for (int c = 0; c < 2; ++c) {
            const double w = (a ? f[0] : 1 - f[0]) * (b ? f[1] : 1 - f[1]) * (c ? f[2] : 1 - f[2]);
            if (w <= 0) continue;
            const openvdb::Coord ijk(base[0] + a, base[1] + b, base[2] + c);
            pa.setValue(ijk, pa.getValue(ijk) + w * mv);
            wa.setValue(ijk, wa.getValue(ijk) + w * mass[p]);
          }
    }
    openvdb::Vec3SGrid::Ptr grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    grid->setName("vel");
    grid->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    openvdb::Vec3SGrid::Accessor va = grid->getAccessor();
    for (openvdb::DoubleGrid::ValueOnCIter it = weight->cbeginValueOn(); it; ++it) {
      if (!(*it > 0)) continue;
      const openvdb::Vec3d u = pa.getValue(it.getCoord()) / *it;
      va.setValue(it.getCoord(), openvdb::Vec3s((float)u[0], (float)u[1], (float)u[2]));
    }
    *out = new mpm_vdb_vector_grid{grid};
    return MPM_VDB_OK;
  } catch (const std::exception &e) {
    say(msg, cap, "OpenVDB failed making the velocity grid", e.what());
  } catch (...) {
    say(msg, cap, "OpenVDB failed making the velocity grid", "unknown exception");
  }
  return MPM_VDB_FAIL;
}

int mpm_vdb_write(const mpm_vdb_grid *g, const char *path, int density,
                  const mpm_vdb_vector_grid *velocity, char *msg, size_t cap) {
  try {
    openvdb::initialize();
    openvdb::GridPtrVec grids;
    grids.push_back(g->grid);
    if (density) {
      openvdb::FloatGrid::Ptr fog = g->grid->deepCopy();
      openvdb::tools::sdfToFogVolume(*fog);
      fog->setName("density");
      grids.push_back(fog);
    }
    if (velocity) grids.push_back(velocity->grid);
    openvdb::io::File file(path);
    file.write(grids);
    file.close();
    return MPM_VDB_OK;
  } catch (const std::exception &e) {
    const std::string what = std::string("cannot write '") + path + "'";
    say(msg, cap, what.c_str(), e.what());
  } catch (...) {
    const std::string what = std::string("cannot write '") + path + "'";
    say(msg, cap, what.c_str(), "unknown exception");
  }
  return MPM_VDB_FAIL;
}

} // extern "C"

namespace {

/* The grid `name` of the file at `path` as a GridT; NULL with a message naming the file, its
   grids, or the grid's type when it is missing or of another type. */
template <typename GridT>
typename GridT::Ptr read_grid(const char *path, const char *name, const char *kind, char *msg,
                              size_t cap) {
  const std::string what = std::string("cannot read '") + path + "'";
  try {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open();
    std::string names;
    for (openvdb::io::File::NameIterator it = file.beginName(); it != file.endName(); ++it)
      names += (names.empty() ? "" : ", ") + it.gridName();
    if (!file.hasGrid(name)) {
      file.close();
      const std::string detail = "it has no grid '" + std::string(name) +
                                 "' (it has: " + (names.empty() ? "none" : names) + ")";
      say(msg, cap, what.c_str(), detail.c_str());
      return nullptr;
    }
    openvdb::GridBase::Ptr base = file.readGrid(name);
    file.close();
    typename GridT::Ptr grid = openvdb::gridPtrCast<GridT>(base);
    if (!grid) {
      const std::string detail =
          "grid '" + std::string(name) + "' is of type " + base->type() + ", not a " + kind;
      say(msg, cap, what.c_str(), detail.c_str());
    }
    return grid;
  } catch (const std::exception &e) {
    say(msg, cap, what.c_str(), e.what());
  } catch (...) {
    say(msg, cap, what.c_str(), "unknown exception");
  }
  return nullptr;
}

} // namespace

extern "C" {

int mpm_vdb_read(const char *path, const char *name, mpm_vdb_grid **out, char *msg, size_t cap) {
  openvdb::FloatGrid::Ptr grid = read_grid<openvdb::FloatGrid>(path, name, "float grid", msg, cap);
  *out = grid ? new mpm_vdb_grid{grid} : nullptr;
  return grid ? MPM_VDB_OK : MPM_VDB_FAIL;
}

int mpm_vdb_read_vector(const char *path, const char *name, mpm_vdb_vector_grid **out, char *msg,
                        size_t cap) {
  openvdb::Vec3SGrid::Ptr grid =
      read_grid<openvdb::Vec3SGrid>(path, name, "vector (Vec3f) grid", msg, cap);
  *out = grid ? new mpm_vdb_vector_grid{grid} : nullptr;
  return grid ? MPM_VDB_OK : MPM_VDB_FAIL;
}

void mpm_vdb_vector_sample(const mpm_vdb_vector_grid *g, const double x[3], double v[3]) {
  openvdb::tools::GridSampler<openvdb::Vec3SGrid, openvdb::tools::BoxSampler> s(*g->grid);
  const openvdb::Vec3s u = s.wsSample(openvdb::Vec3R(x[0], x[1], x[2]));
  for (int d = 0; d < 3; ++d) v[d] = u[d];
}

uint64_t mpm_vdb_vector_active_voxels(const mpm_vdb_vector_grid *g) {
  return g->grid->activeVoxelCount();
}

void mpm_vdb_vector_name(const mpm_vdb_vector_grid *g, char *name, size_t cap) {
  if (name && cap) std::snprintf(name, cap, "%s", g->grid->getName().c_str());
}

void mpm_vdb_vector_grid_destroy(mpm_vdb_vector_grid *g) {
  delete g;
}

void mpm_vdb_grid_info(const mpm_vdb_grid *g, char *name, size_t cap, mpm_vdb_class *cls,
                       double *voxel) {
  if (name && cap) std::snprintf(name, cap, "%s", g->grid->getName().c_str());
  if (cls) {
    switch (g->grid->getGridClass()) {
    case openvdb::GRID_LEVEL_SET:
      *cls = MPM_VDB_CLASS_LEVEL_SET;
      break;
    case openvdb::GRID_FOG_VOLUME:
      *cls = MPM_VDB_CLASS_FOG_VOLUME;
      break;
    case openvdb::GRID_STAGGERED:
      *cls = MPM_VDB_CLASS_STAGGERED;
      break;
    default:
      *cls = MPM_VDB_CLASS_UNKNOWN;
      break;
    }
  }
  if (voxel) *voxel = g->grid->voxelSize()[0];
}

double mpm_vdb_sample(const mpm_vdb_grid *g, const double x[3]) {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> s(*g->grid);
  return s.wsSample(openvdb::Vec3R(x[0], x[1], x[2]));
}

void mpm_vdb_grid_destroy(mpm_vdb_grid *g) {
  delete g;
}

/* The module's entry (vdb_shim.h), found with dlsym. The module is linked with
 * -Bsymbolic-functions, so the functions above bind inside it and never to the loader's
 * wrappers of the same names. */
const mpm_vdb_table *mpm_vdb_module_table(void) {
  static const mpm_vdb_table table = {MPM_VDB_TABLE_VERSION, mpm_vdb_levelset_from_spheres,
                                      mpm_vdb_smooth,        mpm_vdb_mesh,
                                      mpm_vdb_active_voxels, mpm_vdb_velocity_from_particles,
                                      mpm_vdb_write,         mpm_vdb_read,
                                      mpm_vdb_grid_info,     mpm_vdb_sample,
                                      mpm_vdb_grid_destroy,  mpm_vdb_read_vector,
                                      mpm_vdb_vector_sample, mpm_vdb_vector_active_voxels,
                                      mpm_vdb_vector_name,   mpm_vdb_vector_grid_destroy,
                                      set_allocator};
  return &table;
}

} // extern "C"
