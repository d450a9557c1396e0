/* scene_json_shape.c - the shapes, bodies and colliders of the JSON scene format: shape
 * objects (box, sphere, cylinder and mesh for bodies; box, sphere, cylinder and halfspace for
 * colliders) with mesh files resolved against the scene file's directory, the check that each
 * body's bounding box lies inside the domain minus the wall band, the 'bodies' array and the
 * 'colliders' array with their motion (velocity and spin, or keyframes), and the 'forces' array
 * (body-force regions: a collider's shape, motion and window with an acceleration).
 * Part of the scene parser of scene_json.c (shared declarations: scene_json_parts.h). */
#include "scene/json_check.h"
#include "core/alloc.h"
#include "io/input_file.h"
#include "scene/mesh.h"
#include "scene/scene.h"
#include "scene/scene_json_parts.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const BODY_KEYS[] = {"name",
                                        "shape",
                                        "material",
                                        "velocity",
                                        "angular_velocity",
                                        "particles_per_cell",
                                        "jitter",
                                        "seed",
                                        "domains",
                                        "domain_release",
                                        "enrichment",
                                        "enrichment_exit",
                                        "enrichment_exit_wait",
                                        "enrichment_hourglass",
                                        "enrichment_contact",
                                        "enrichment_surface_contact",
                                        "enrichment_self_contact",
                                        "enrichment_metric",
                                        "hourglass",
                                        "temperature",
                                        NULL};
static const char *const RELEASE_KEYS[] = {"time", "min", "max", NULL};
static const char *const COLLIDER_KEYS[] = {"name",   "shape",  "inside_out",  "rule", "friction",
                                            "motion", "active", "temperature", NULL};
static const char *const FORCE_KEYS[] = {"name",         "shape", "inside_out", "motion", "active",
                                         "acceleration", "drag",  "schedule",   NULL};
static const char *const MOTION_KEYS[] = {"velocity", "axis", "angular_speed", "keyframes", NULL};
static const char *const KEYFRAME_KEYS[] = {"time", "translation", "angle", NULL};

static const char *const BOX_KEYS[] = {"type", "center", "half_extent", NULL};
static const char *const SPHERE_KEYS[] = {"type", "center", "radius", NULL};
static const char *const CYLINDER_KEYS[] = {"type", "center",      "radius",
                                            "axis", "half_height", NULL};
static const char *const MESH_KEYS[] = {"type", "file", "center", "scale", "max_file_mb", NULL};
static const char *const HALFSPACE_KEYS[] = {"type", "point", "normal", NULL};
static const char *const REVOLVE_KEYS[] = {"type", "center", "axis", "profile", NULL};

static const char *const BODY_SHAPE_NAMES[] = {"box", "sphere", "cylinder", "mesh", NULL};
static const mpm_shape_kind BODY_SHAPE_KINDS[] = {MPM_SHAPE_BOX, MPM_SHAPE_SPHERE,
                                                  MPM_SHAPE_CYLINDER, MPM_SHAPE_MESH};
static const char *const COLLIDER_SHAPE_NAMES[] = {"box",       "sphere",  "cylinder",
                                                   "halfspace", "revolve", NULL};
static const mpm_shape_kind COLLIDER_SHAPE_KINDS[] = {
    MPM_SHAPE_BOX, MPM_SHAPE_SPHERE, MPM_SHAPE_CYLINDER, MPM_SHAPE_HALFSPACE, MPM_SHAPE_REVOLVE};

/* ---- small helpers -------------------------------------------------------------------- */

/* Resolve `file` against the directory of the scene file; -1 when it does not fit. */
static int resolve_path(const char *scene_path, const char *file, char *out, size_t cap) {
  const char *slash = strrchr(scene_path, '/');
  int n;
  if (file[0] == '/' || !slash)
    n = snprintf(out, cap, "%s", file);
  else
    n = snprintf(out, cap, "%.*s/%s", (int)(slash - scene_path), scene_path, file);
  return (n < 0 || (size_t)n >= cap) ? -1 : 0;
}

/* "[0.1, 0.2, 0.3]" with '.' decimals. */
static const char *format_vec3(const double v[3], char *buf, size_t cap) {
  char a[40], b[40], d[40];
  snprintf(buf, cap, "[%s, %s, %s]", mpm_json_format_short(v[0], a, sizeof a),
           mpm_json_format_short(v[1], b, sizeof b), mpm_json_format_short(v[2], d, sizeof d));
  return buf;
}

/* ---- shapes --------------------------------------------------------------------------- */

/* Bounding box of a mesh body: the mesh's box scaled about its centre, moved to `center`. */
static int mesh_bounds(mpm_json_ctx *c, mpm_shape_desc *sh, double lo[3], double hi[3], char *note,
                       size_t note_cap) {
  char why[128];
  FILE *f = mpm_open_input(sh->mesh_path, NULL, why, sizeof why);
  if (!f)
    return mpm_json_fail_at(c, "file", MPM_ERR_IO, "cannot open mesh file '%s': %s", sh->mesh_path,
                            why);
  errno = 0;
  (void)fgetc(f);
  int bad = ferror(f), e = errno;
  fclose(f);
  if (bad)
    return mpm_json_fail_at(c, "file", MPM_ERR_IO, "cannot read mesh file '%s': %s", sh->mesh_path,
                            strerror(e ? e : EIO));
  mpm_mesh mesh;
  memset(&mesh, 0, sizeof mesh);
  mpm_error merr;
  mpm_error_clear(&merr);
  const double max_mb = sh->mesh_max_mb > 0 ? sh->mesh_max_mb : MPM_MESH_MAX_MB;
  mpm_status st = mpm_mesh_load_max(sh->mesh_path, max_mb * 1024 * 1024, &mesh, &merr);
  if (st != MPM_OK)
    return mpm_json_fail_at(c, "file", st, "cannot use mesh file '%s': %s", sh->mesh_path,
                            merr.message);
  /* a body must enclose a volume: the mesh must be closed (every edge shared by two
     triangles) and its triangles must span a volume, or inside and outside mean nothing */
  mpm_mesh_edges edges;
  if (mpm_mesh_edge_check(&mesh, &edges)) {
    mpm_mesh_free(&mesh);
    return mpm_json_fail_at(c, "file", MPM_ERR_NOMEM, "out of memory checking mesh file '%s'",
                            sh->mesh_path);
  }
  const long open_edges = edges.boundary;
  /* where the file has the faces of its first non-manifold edge (refused below, after the
     checks that say more of a flat or open mesh) */
  char where[160] = "";
  size_t where_len = 0;
  for (int q = 0; q < edges.shared && q < 4 && mesh.triangle_source; ++q)
    where_len += (size_t)snprintf(where + where_len, sizeof where - where_len, "%s%d",
                                  q ? ", " : "", mesh.triangle_source[edges.triangles[q]]);
  const char *where_what = mesh.source_is_line ? "lines" : "face elements";
  double area = 0, volume = 0;
  for (int t = 0; t < mesh.triangle_count; ++t) {
    const double *a = mesh.vertices + 3 * mesh.triangles[3 * t];
    const double *b = mesh.vertices + 3 * mesh.triangles[3 * t + 1];
    const double *q = mesh.vertices + 3 * mesh.triangles[3 * t + 2];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    volume += (a[0] * n[0] + a[1] * n[1] + a[2] * n[2]) / 6; /* divergence theorem */
  }
  double mlo[3], mhi[3];
  mpm_mesh_bounds(&mesh, mlo, mhi);
  const int triangles = mesh.triangle_count;
  mpm_mesh_free(&mesh);
  const double box = (mhi[0] - mlo[0]) * (mhi[1] - mlo[1]) * (mhi[2] - mlo[2]);
  if (open_edges > 0)
    return mpm_json_fail_at(c, "file", MPM_ERR_INVALID,
                            "mesh file '%s' is not closed: %ld edges belong to one triangle only "
                            "(a body needs a watertight mesh to tell inside from outside)",
                            sh->mesh_path, open_edges);
  if (!(area > 0))
    return mpm_json_fail_at(c, "file", MPM_ERR_INVALID,
                            "mesh file '%s' has no triangle of nonzero area (%d triangles)",
                            sh->mesh_path, triangles);
  if (!(fabs(volume) > 1e-9 * box) || !(box > 0))
    return mpm_json_fail_at(c, "file", MPM_ERR_INVALID,
                            "mesh file '%s' encloses no volume (it is flat or its triangles "
                            "cancel out)",
                            sh->mesh_path);
  if (edges.non_manifold > 0)
    return mpm_json_fail_at(
        c, "file", MPM_ERR_INVALID,
        "mesh file '%s' is not a closed 2-manifold: the edge between vertices %d and %d (counted "
        "from 1) belongs to %d triangles (the faces at %s %s%s), %ld such edge%s in all; a body "
        "needs a surface where every edge joins exactly two faces (touching or overlapping "
        "shells make inside and outside ambiguous: join them into one)",
        sh->mesh_path, edges.a + 1, edges.b + 1, edges.shared, where_what, where,
        edges.shared > 4 ? ", ..." : "", edges.non_manifold, edges.non_manifold == 1 ? "" : "s");
  char ex[3][40], sc[40];
  for (int d = 0; d < 3; ++d) mpm_json_format_short(mhi[d] - mlo[d], ex[d], sizeof ex[d]);
  snprintf(note, note_cap, " (the mesh is %s x %s x %s in file units, times scale %s)", ex[0],
           ex[1], ex[2], mpm_json_format_short(sh->mesh_scale, sc, sizeof sc));
  sh->mesh_volume = fabs(volume) * sh->mesh_scale * sh->mesh_scale * sh->mesh_scale;
  for (int d = 0; d < 3; ++d) {
    double half = 0.5 * sh->mesh_scale * (mhi[d] - mlo[d]);
    lo[d] = sh->center[d] - half;
    hi[d] = sh->center[d] + half;
  }
  return 0;
}

/* Do the segments p0-p1 and q0-q1 of the plane cross or touch? */
static int segments_meet(const double p0[2], const double p1[2], const double q0[2],
                         const double q1[2]) {
  const double d1 = (p1[0] - p0[0]) * (q0[1] - p0[1]) - (p1[1] - p0[1]) * (q0[0] - p0[0]);
  const double d2 = (p1[0] - p0[0]) * (q1[1] - p0[1]) - (p1[1] - p0[1]) * (q1[0] - p0[0]);
  const double d3 = (q1[0] - q0[0]) * (p0[1] - q0[1]) - (q1[1] - q0[1]) * (p0[0] - q0[0]);
  const double d4 = (q1[0] - q0[0]) * (p1[1] - q0[1]) - (q1[1] - q0[1]) * (p1[0] - q0[0]);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return 1;
  /* touching (collinear or an end on the other segment): bounding boxes overlap and one end
     is exactly on the other's line */
  const int zero = d1 == 0 || d2 == 0 || d3 == 0 || d4 == 0;
  return zero && fmin(p0[0], p1[0]) <= fmax(q0[0], q1[0]) &&
         fmin(q0[0], q1[0]) <= fmax(p0[0], p1[0]) && fmin(p0[1], p1[1]) <= fmax(q0[1], q1[1]) &&
         fmin(q0[1], q1[1]) <= fmax(p0[1], p1[1]);
}

/* shape.profile of a revolve: [[radius, height], ...], 3 to MPM_PROFILE_MAX points, from the
 * axis (radius 0) back to the axis, radii >= 0, consecutive points distinct, and no two
 * segments meeting except neighbours at their shared point (a simple outline). */
static int parse_profile(mpm_json_ctx *c, const cJSON *shape, mpm_shape_desc *sh) {
  const cJSON *arr = NULL;
  const char *what = "an array of [radius, height] points from the axis back to the axis";
  if (mpm_sj_get_array(c, shape, "profile", 1, what, &arr) < 0) return -1;
  const int n = cJSON_GetArraySize(arr);
  if (n < 3 || n > MPM_PROFILE_MAX)
    return mpm_json_fail_at(c, "profile", MPM_ERR_INVALID, "expected 3 to %d points, got %d",
                            MPM_PROFILE_MAX, n);
  size_t old = mpm_json_push_key(c, "profile");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    const cJSON *r = cJSON_IsArray(e) ? cJSON_GetArrayItem(e, 0) : NULL;
    const cJSON *h = cJSON_IsArray(e) ? cJSON_GetArrayItem(e, 1) : NULL;
    if (!r || !h || cJSON_GetArraySize(e) != 2 || !cJSON_IsNumber(r) || !cJSON_IsNumber(h) ||
        !isfinite(r->valuedouble) || !isfinite(h->valuedouble))
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "expected a point [radius, height] of two finite "
                           "numbers in m");
    sh->profile[i][0] = r->valuedouble;
    sh->profile[i][1] = h->valuedouble;
    if (sh->profile[i][0] < 0)
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected a radius >= 0 m, got %g",
                           sh->profile[i][0]);
    if ((i == 0 || i == n - 1) && sh->profile[i][0] != 0)
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "expected radius 0 (the profile starts and ends on the axis), got %g",
                           sh->profile[i][0]);
    if (i > 0 && sh->profile[i][0] == sh->profile[i - 1][0] &&
        sh->profile[i][1] == sh->profile[i - 1][1])
      return mpm_json_fail(c, MPM_ERR_INVALID, "expected a point different from the one before");
    mpm_json_pop(c, o2);
  }
  sh->profile_count = n;
  for (int a = 0; a + 1 < n; ++a)
    for (int b = a + 2; b + 1 < n; ++b) {
      if (a == 0 && b == n - 2 && sh->profile[0][1] == sh->profile[n - 1][1])
        continue; /* first and last segments end at the same point on the axis */
      if (segments_meet(sh->profile[a], sh->profile[a + 1], sh->profile[b], sh->profile[b + 1]))
        return mpm_json_fail(c, MPM_ERR_INVALID,
                             "expected a simple outline, but segment %d-%d meets segment %d-%d", a,
                             a + 1, b, b + 1);
    }
  mpm_json_pop(c, old);
  return 0;
}

/* obj.shape at the current path (for_body: bodies allow meshes, colliders half-spaces).
 * scene_path resolves mesh files. */
static int parse_shape(mpm_json_ctx *c, const cJSON *parent, int for_body, const char *scene_path,
                       mpm_shape_desc *sh) {
  const cJSON *n = mpm_json_get(parent, "shape");
  if (!n) return mpm_json_missing(c, "shape");
  size_t old = mpm_json_push_key(c, "shape");
  const char *const *names = for_body ? BODY_SHAPE_NAMES : COLLIDER_SHAPE_NAMES;
  const mpm_shape_kind *kinds = for_body ? BODY_SHAPE_KINDS : COLLIDER_SHAPE_KINDS;
  if (mpm_json_expect_object(c, n, "a shape object with a 'type'") < 0) return -1;
  const cJSON *type = mpm_json_get(n, "type");
  if (!type)
    return mpm_json_fail(c, MPM_ERR_INVALID, "missing required key 'type' (one of %s)",
                         for_body ? "box, sphere, cylinder, mesh"
                                  : "box, sphere, cylinder, halfspace, revolve");
  if (cJSON_IsString(type) && type->valuestring) {
    if (!for_body && strcmp(type->valuestring, "mesh") == 0)
      return mpm_json_fail_at(c, "type", MPM_ERR_INVALID,
                              "expected one of box, sphere, cylinder, halfspace, revolve, got "
                              "'mesh' (meshes can only be bodies)");
    if (for_body && strcmp(type->valuestring, "halfspace") == 0)
      return mpm_json_fail_at(c, "type", MPM_ERR_INVALID,
                              "expected one of box, sphere, cylinder, mesh, got 'halfspace' "
                              "(a half-space is infinite; it can only be a collider)");
    if (for_body && strcmp(type->valuestring, "revolve") == 0)
      return mpm_json_fail_at(c, "type", MPM_ERR_INVALID,
                              "expected one of box, sphere, cylinder, mesh, got 'revolve' "
                              "(a solid of revolution can only be a collider)");
  }
  int t = 0;
  if (mpm_json_enum(c, n, "type", 1, names, &t) < 0) return -1;
  sh->kind = kinds[t];
  const mpm_json_range any_m = mpm_json_any("m"), pos_m = mpm_json_gt(0, "m");
  switch (sh->kind) {
  case MPM_SHAPE_BOX:
    if (mpm_json_check_keys(c, n, BOX_KEYS, "for a box shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_vec3(c, n, "half_extent", 1, pos_m, sh->half_extent) < 0)
      return -1;
    break;
  case MPM_SHAPE_SPHERE:
    if (mpm_json_check_keys(c, n, SPHERE_KEYS, "for a sphere shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "radius", 1, pos_m, &sh->radius) < 0)
      return -1;
    break;
  case MPM_SHAPE_CYLINDER:
    if (mpm_json_check_keys(c, n, CYLINDER_KEYS, "for a cylinder shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "radius", 1, pos_m, &sh->radius) < 0 ||
        mpm_json_direction(c, n, "axis", 0, sh->axis) < 0)
      return -1;
    if (for_body ? mpm_json_number(c, n, "half_height", 1, pos_m, &sh->half_height) < 0
                 : mpm_json_number(c, n, "half_height", 0, mpm_json_ge(0, "m, 0 = infinite"),
                                   &sh->half_height) < 0)
      return -1;
    break;
  case MPM_SHAPE_MESH: {
    char file[MPM_PATH_MAX];
    if (mpm_json_check_keys(c, n, MESH_KEYS, "for a mesh shape") < 0 ||
        mpm_json_string(c, n, "file", 1, file, sizeof file) < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_number(c, n, "scale", 0, mpm_json_gt(0, "factor"), &sh->mesh_scale) < 0 ||
        mpm_json_number(c, n, "max_file_mb", 0,
                        mpm_json_in('(', 0, 1048576, ']', "MiB, the largest mesh file read"),
                        &sh->mesh_max_mb) < 0)
      return -1;
    if (resolve_path(scene_path, file, sh->mesh_path, sizeof sh->mesh_path) < 0)
      return mpm_json_fail_at(c, "file", MPM_ERR_INVALID,
                              "expected a path of at most %d bytes once resolved against the "
                              "scene file's directory, got a longer one",
                              MPM_PATH_MAX - 1);
    break;
  }
  case MPM_SHAPE_HALFSPACE:
    if (mpm_json_check_keys(c, n, HALFSPACE_KEYS, "for a halfspace shape") < 0 ||
        mpm_json_vec3(c, n, "point", 1, any_m, sh->center) < 0 ||
        mpm_json_direction(c, n, "normal", 1, sh->axis) < 0)
      return -1;
    break;
  case MPM_SHAPE_REVOLVE:
    if (mpm_json_check_keys(c, n, REVOLVE_KEYS, "for a revolve shape") < 0 ||
        mpm_json_vec3(c, n, "center", 1, any_m, sh->center) < 0 ||
        mpm_json_direction(c, n, "axis", 0, sh->axis) < 0 || parse_profile(c, n, sh) < 0)
      return -1;
    break;
  }
  mpm_json_pop(c, old);
  return 0;
}

/* Axis-aligned bounding box of a box, sphere or cylinder. */
static void shape_bounds(const mpm_shape_desc *sh, double lo[3], double hi[3]) {
  for (int d = 0; d < 3; ++d) {
    double h = 0;
    if (sh->kind == MPM_SHAPE_BOX) h = sh->half_extent[d];
    if (sh->kind == MPM_SHAPE_SPHERE) h = sh->radius;
    if (sh->kind == MPM_SHAPE_CYLINDER) {
      double a = sh->axis[d];
      h = sh->half_height * fabs(a) + sh->radius * sqrt(fmax(0.0, 1.0 - a * a));
    }
    lo[d] = sh->center[d] - h;
    hi[d] = sh->center[d] + h;
  }
}

/* The body's bounding box must lie inside the domain minus the wall band; the current path
 * is the body. */
static int check_inside(mpm_json_ctx *c, const mpm_scene *s, const double lo[3], const double hi[3],
                        const char *note) {
  double blo[3], bhi[3], longest = 0;
  for (int d = 0; d < 3; ++d) {
    blo[d] = s->box_min[d] + s->wall_cells * s->dx;
    bhi[d] = s->box_max[d] - s->wall_cells * s->dx;
    longest = fmax(longest, s->box_max[d] - s->box_min[d]);
  }
  const double tol = 1e-9 * longest;
  char out[400], num[40];
  size_t o = 0;
  out[0] = '\0';
  for (int d = 0; d < 3; ++d)
    for (int side = 0; side < 2; ++side) {
      double over = side ? hi[d] - bhi[d] : blo[d] - lo[d];
      if (!(over > tol)) continue;
      int w = snprintf(out + o, sizeof out - o, "%s%s m on %c%c", o ? ", " : "",
                       mpm_json_format_short(over, num, sizeof num), side ? '+' : '-',
                       mpm_sj_axis_name[d]);
      if (w > 0 && (size_t)w < sizeof out - o) o += (size_t)w;
    }
  if (o == 0) return 0;
  char a[128], b[128], la[128], lb[128], dxs[40];
  return mpm_json_fail_at(
      c, "shape", MPM_ERR_INVALID,
      "expected the body's bounding box to lie inside the domain minus the wall band of %d "
      "cells of %s m, i.e. inside %s .. %s m, got %s .. %s m%s: it sticks out by %s",
      s->wall_cells, mpm_json_format_short(s->dx, dxs, sizeof dxs), format_vec3(blo, la, sizeof la),
      format_vec3(bhi, lb, sizeof lb), format_vec3(lo, a, sizeof a), format_vec3(hi, b, sizeof b),
      note, out);
}

/* ---- bodies --------------------------------------------------------------------------- */

/* domain_release: [{"time": s, "min": [x, y, z], "max": [x, y, z]}, ...] */
static int parse_releases(mpm_json_ctx *c, const cJSON *node, mpm_body_desc *b) {
  const cJSON *arr = NULL;
  const int has =
      mpm_sj_get_array(c, node, "domain_release", 0, "an array of {time, min, max} objects", &arr);
  if (has <= 0) return has;
  if (!b->domains)
    return mpm_json_fail_at(c, "domain_release", MPM_ERR_INVALID,
                            "applies only to a body with \"domains\": true");
  const int n = cJSON_GetArraySize(arr);
  if (n > MPM_MAX_RELEASES)
    return mpm_json_fail_at(c, "domain_release", MPM_ERR_INVALID,
                            "expected at most %d entries, got %d", MPM_MAX_RELEASES, n);
  size_t old = mpm_json_push_key(c, "domain_release");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_domain_release *r = &b->release[i];
    if (mpm_json_expect_object(c, e, "an object with keys time, min, max") < 0 ||
        mpm_json_check_keys(c, e, RELEASE_KEYS, NULL) < 0 ||
        mpm_json_number(c, e, "time", 1, mpm_json_ge(0, "s"), &r->time) < 0 ||
        mpm_json_vec3(c, e, "min", 1, mpm_json_any("m"), r->min) < 0 ||
        mpm_json_vec3(c, e, "max", 1, mpm_json_any("m"), r->max) < 0)
      return -1;
    for (int d = 0; d < 3; ++d)
      if (!(r->max[d] > r->min[d]))
        return mpm_json_fail_at(c, "max", MPM_ERR_INVALID,
                                "expected max[%d] > min[%d] = %g, got %g", d, d, r->min[d],
                                r->max[d]);
    b->release_count = i + 1;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

static int parse_body(mpm_json_ctx *c, const cJSON *node, int index, int named, mpm_scene *s,
                      mpm_body_desc *b) {
  if (mpm_json_expect_object(c, node, "a body object") < 0 ||
      mpm_json_check_keys(c, node, BODY_KEYS, NULL) < 0)
    return -1;
  snprintf(b->name, sizeof b->name, "body%d", index);
  long long seed = b->seed;
  if (mpm_json_string(c, node, "name", 0, b->name, sizeof b->name) < 0 ||
      parse_shape(c, node, 1, s->path, &b->shape) < 0 ||
      mpm_sj_parse_body_material(c, node, named, s, b) < 0 ||
      mpm_json_vec3(c, node, "velocity", 0, mpm_json_any("m/s"), b->velocity) < 0 ||
      mpm_json_vec3(c, node, "angular_velocity", 0, mpm_json_any("rad/s"), b->angular_velocity) <
          0 ||
      mpm_json_number(c, node, "particles_per_cell", 0,
                      mpm_json_in('(', 0, 1000, ']', "particles per grid cell"),
                      &b->particles_per_cell) < 0 ||
      mpm_json_number(c, node, "jitter", 0,
                      mpm_json_in('[', 0, 1, ']', "fraction of the particle spacing"),
                      &b->jitter) < 0 ||
      mpm_json_integer(c, node, "seed", 0, mpm_json_in('[', 0, 4294967295.0, ']', NULL), &seed) < 0)
    return -1;
  b->seed = (unsigned)seed;
  if (mpm_json_bool(c, node, "domains", 0, &b->domains) < 0 || parse_releases(c, node, b) < 0 ||
      mpm_sj_parse_temperature(c, node, &b->has_temperature, &b->temperature) < 0)
    return -1;
  /* Zhu sec. 5.1 uses epsilon = 0.6; off by default (docs/scene-format.md: dynamic
   * enrichment) */
  b->enrichment = 0;
  static const char *const enrichment_keys[] = {"enrichment",
                                                "enrichment_exit",
                                                "enrichment_hourglass",
                                                "enrichment_contact",
                                                "enrichment_metric",
                                                "hourglass",
                                                "enrichment_surface_contact",
                                                "enrichment_self_contact",
                                                "enrichment_exit_wait"};
  for (size_t k = 0; k < sizeof enrichment_keys / sizeof enrichment_keys[0]; ++k)
    if (mpm_json_get(node, enrichment_keys[k]) && !b->domains)
      return mpm_json_fail_at(c, enrichment_keys[k], MPM_ERR_INVALID,
                              "applies only to a body with \"domains\": true");
  static const char *const metric_names[] = {"condition", "frobenius", NULL};
  b->enrichment_metric = 0;
  if (mpm_json_enum(c, node, "enrichment_metric", 0, metric_names, &b->enrichment_metric) < 0)
    return -1;
  static const char *const hourglass_names[] = {"enriched", "all", NULL};
  b->hourglass = 0;
  if (mpm_json_enum(c, node, "hourglass", 0, hourglass_names, &b->hourglass) < 0) return -1;
  if (mpm_json_number(c, node, "enrichment", 0,
                      mpm_json_in('[', 0, 1, ']', "threshold on the enrichment metric K(F)"),
                      &b->enrichment) < 0)
    return -1;
  b->enrichment_exit = b->enrichment > 0.95 ? b->enrichment : 0.95;
  char exit_note[96];
  snprintf(exit_note, sizeof exit_note,
           "K(F) above which an enriched particle returns to the grid, at least enrichment (%g)",
           b->enrichment);
  if (mpm_json_number(c, node, "enrichment_exit", 0,
                      mpm_json_in('[', b->enrichment, 1, ']', exit_note), &b->enrichment_exit) < 0)
    return -1;
  b->enrichment_exit_wait = 0;
  if (mpm_json_number(c, node, "enrichment_exit_wait", 0,
                      mpm_json_in('[', 0, 1e9, ']',
                                  "seconds an enriched particle stays relaxed before it returns"),
                      &b->enrichment_exit_wait) < 0)
    return -1;
  b->enrichment_hourglass = 0;
  if (mpm_json_number(c, node, "enrichment_hourglass", 0,
                      mpm_json_in('[', 0, 1, ']',
                                  "threshold on the hourglass strain of a particle's hexahedron"),
                      &b->enrichment_hourglass) < 0)
    return -1;
  b->enrichment_contact = 0;
  if (mpm_json_bool(c, node, "enrichment_contact", 0, &b->enrichment_contact) < 0) return -1;
  b->enrichment_surface_contact = 1;
  if (mpm_json_bool(c, node, "enrichment_surface_contact", 0, &b->enrichment_surface_contact) < 0)
    return -1;
  b->enrichment_self_contact = 1;
  if (mpm_json_bool(c, node, "enrichment_self_contact", 0, &b->enrichment_self_contact) < 0)
    return -1;
  if (b->domains && b->jitter != 0)
    return mpm_json_fail_at(c, "jitter", MPM_ERR_INVALID,
                            "expected 0 with \"domains\": true (particle domains are the cells "
                            "of the body's lattice), got %g",
                            b->jitter);
  double lo[3], hi[3];
  char note[200] = "";
  if (b->shape.kind == MPM_SHAPE_MESH) {
    size_t old = mpm_json_push_key(c, "shape");
    if (mesh_bounds(c, &b->shape, lo, hi, note, sizeof note) < 0) return -1;
    mpm_json_pop(c, old);
  } else {
    shape_bounds(&b->shape, lo, hi);
  }
  memcpy(b->shape.bounds_lo, lo, sizeof b->shape.bounds_lo);
  memcpy(b->shape.bounds_hi, hi, sizeof b->shape.bounds_hi);
  return check_inside(c, s, lo, hi, note);
}

int mpm_sj_parse_bodies(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  if (mpm_sj_get_array(c, root, "bodies", 1, "an array of body objects", &arr) < 0) return -1;
  int n = cJSON_GetArraySize(arr);
  if (n == 0)
    return mpm_json_fail_at(c, "bodies", MPM_ERR_INVALID,
                            "expected at least one body, got an empty array");
  s->bodies = mpm_alloc((size_t)n * sizeof *s->bodies);
  if (!s->bodies) return mpm_sj_fail_nomem(c, "bodies");
  const int named = s->material_count;
  size_t old = mpm_json_push_key(c, "bodies");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_body_desc b = mpm_body_desc_default();
    if (parse_body(c, e, i, named, s, &b) < 0) return -1;
    s->bodies[s->body_count++] = b;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

/* ---- colliders ------------------------------------------------------------------------ */

static int parse_keyframes(mpm_json_ctx *c, const cJSON *arr, mpm_motion_desc *m) {
  int n = cJSON_GetArraySize(arr);
  if (n == 0) return 0;
  m->keyframes = mpm_alloc((size_t)n * sizeof *m->keyframes);
  if (!m->keyframes) return mpm_sj_fail_nomem(c, "keyframes");
  size_t old = mpm_json_push_key(c, "keyframes");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    mpm_keyframe k;
    memset(&k, 0, sizeof k);
    char note[64];
    snprintf(note, sizeof note, "s, later than keyframes[%d].time", i - 1);
    mpm_json_range tr = i == 0 ? mpm_json_ge(0, "s") : mpm_json_gt(m->keyframes[i - 1].time, note);
    if (mpm_json_expect_object(c, e, "a keyframe object with keys time, translation, angle") < 0 ||
        mpm_json_check_keys(c, e, KEYFRAME_KEYS, NULL) < 0 ||
        mpm_json_number(c, e, "time", 1, tr, &k.time) < 0 ||
        mpm_json_vec3(c, e, "translation", 0, mpm_json_any("m"), k.translation) < 0 ||
        mpm_json_number(c, e, "angle", 0, mpm_json_any("rad"), &k.angle) < 0)
      return -1;
    m->keyframes[m->keyframe_count++] = k;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

static int parse_motion(mpm_json_ctx *c, const cJSON *collider, mpm_motion_desc *m) {
  const cJSON *n = mpm_json_get(collider, "motion");
  if (!n) return 0;
  size_t old = mpm_json_push_key(c, "motion");
  if (mpm_json_expect_object(c, n, "a motion object") < 0 ||
      mpm_json_check_keys(c, n, MOTION_KEYS, NULL) < 0)
    return -1;
  int has_v = mpm_json_vec3(c, n, "velocity", 0, mpm_json_any("m/s"), m->velocity);
  if (has_v < 0 || mpm_json_direction(c, n, "axis", 0, m->axis) < 0) return -1;
  int has_w = mpm_json_number(c, n, "angular_speed", 0, mpm_json_any("rad/s"), &m->angular_speed);
  if (has_w < 0) return -1;
  const cJSON *kf = NULL;
  int has_k = mpm_sj_get_array(c, n, "keyframes", 0, "an array of keyframe objects", &kf);
  if (has_k < 0) return -1;
  if (has_k && cJSON_GetArraySize(kf) > 0 && (has_v || has_w))
    return mpm_json_fail(c, MPM_ERR_INVALID,
                         "expected either 'keyframes' or 'velocity'/'angular_speed', got both "
                         "(with keyframes the motion follows them alone)");
  if (has_k && parse_keyframes(c, kf, m) < 0) return -1;
  mpm_json_pop(c, old);
  return 0;
}

/* "active": [t0, t1], 0 <= t0 < t1 (s): when the collider acts. */
static int parse_active(mpm_json_ctx *c, const cJSON *e, double active[2]) {
  const cJSON *a = mpm_json_get(e, "active");
  if (!a) return 0;
  char buf[64];
  if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != 2 || !cJSON_IsNumber(a->child) ||
      !cJSON_IsNumber(a->child->next))
    return mpm_json_fail_at(c, "active", MPM_ERR_INVALID,
                            "expected [start, end] in seconds (two numbers), got %s",
                            mpm_json_describe(a, buf, sizeof buf));
  const double t0 = a->child->valuedouble, t1 = a->child->next->valuedouble;
  if (!(t0 >= 0) || !(t1 > t0) || !isfinite(t1))
    return mpm_json_fail_at(c, "active", MPM_ERR_INVALID,
                            "expected 0 <= start < end (s), got [%g, %g]", t0, t1);
  active[0] = t0;
  active[1] = t1;
  return 0;
}

int mpm_sj_parse_colliders(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  int has = mpm_sj_get_array(c, root, "colliders", 0, "an array of collider objects", &arr);
  if (has <= 0) return has;
  int n = cJSON_GetArraySize(arr);
  if (n == 0) return 0;
  s->colliders = mpm_alloc((size_t)n * sizeof *s->colliders);
  if (!s->colliders) return mpm_sj_fail_nomem(c, "colliders");
  size_t old = mpm_json_push_key(c, "colliders");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    /* counted before parsing so that mpm_scene_free releases its keyframes on error */
    mpm_collider_desc *d = &s->colliders[s->collider_count++];
    *d = mpm_collider_desc_default();
    snprintf(d->name, sizeof d->name, "collider%d", i);
    int rule = (int)d->rule;
    if (mpm_json_expect_object(c, e, "a collider object") < 0 ||
        mpm_json_check_keys(c, e, COLLIDER_KEYS, NULL) < 0 ||
        mpm_json_string(c, e, "name", 0, d->name, sizeof d->name) < 0 ||
        parse_shape(c, e, 0, s->path, &d->shape) < 0 ||
        mpm_json_bool(c, e, "inside_out", 0, &d->inside_out) < 0 ||
        mpm_json_enum(c, e, "rule", 0, mpm_sj_rule_names, &rule) < 0 ||
        mpm_json_number(c, e, "friction", 0, mpm_json_ge(0, "Coulomb coefficient"), &d->friction) <
            0 ||
        parse_motion(c, e, &d->motion) < 0 || parse_active(c, e, d->active) < 0 ||
        mpm_sj_parse_temperature(c, e, &d->heat_source, &d->temperature) < 0)
      return -1;
    d->rule = (mpm_boundary_rule)rule;
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}

/* ---- body-force regions ----------------------------------------------------------------- */

int mpm_sj_parse_forces(mpm_json_ctx *c, const cJSON *root, mpm_scene *s) {
  const cJSON *arr = NULL;
  int has = mpm_sj_get_array(c, root, "forces", 0, "an array of body-force region objects", &arr);
  if (has <= 0) return has;
  int n = cJSON_GetArraySize(arr);
  if (n == 0) return 0;
  s->forces = mpm_alloc((size_t)n * sizeof *s->forces);
  if (!s->forces) return mpm_sj_fail_nomem(c, "forces");
  size_t old = mpm_json_push_key(c, "forces");
  int i = 0;
  for (const cJSON *e = arr->child; e; e = e->next, ++i) {
    size_t o2 = mpm_json_push_index(c, i);
    /* counted before parsing so that mpm_scene_free releases its keyframes on error */
    mpm_force_desc *f = &s->forces[s->force_count++];
    *f = mpm_force_desc_default();
    mpm_collider_desc *d = &f->region;
    snprintf(d->name, sizeof d->name, "force%d", i);
    if (mpm_json_expect_object(c, e, "a body-force region object") < 0 ||
        mpm_json_check_keys(c, e, FORCE_KEYS, NULL) < 0 ||
        mpm_json_string(c, e, "name", 0, d->name, sizeof d->name) < 0 ||
        parse_shape(c, e, 0, s->path, &d->shape) < 0 ||
        mpm_json_bool(c, e, "inside_out", 0, &d->inside_out) < 0 ||
        parse_motion(c, e, &d->motion) < 0 || parse_active(c, e, d->active) < 0 ||
        mpm_json_vec3(c, e, "acceleration", 0, mpm_json_any("m/s^2"), f->acceleration) < 0 ||
        mpm_json_number(c, e, "drag", 0, mpm_json_in('[', 0, 1e6, ']', "drag rate, 1/s"),
                        &f->drag) < 0 ||
        mpm_sj_parse_schedule(c, e, "schedule", f->schedule, &f->schedule_count) < 0)
      return -1;
    if (!mpm_json_get(e, "acceleration") && !mpm_json_get(e, "drag"))
      return mpm_json_fail(c, MPM_ERR_INVALID,
                           "a body-force region needs \"acceleration\" or \"drag\" (or both)");
    mpm_json_pop(c, o2);
  }
  mpm_json_pop(c, old);
  return 0;
}
