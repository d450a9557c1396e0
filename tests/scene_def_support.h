/* scene_def_support.h - what the scene def's tests (test_scene_def.c, test_scene_def_more.c)
 * share: a def against the same scene written as JSON by hand, and a def's refusal.
 *
 * The truth is the JSON parser: a def and the hand-written text must give the same scene
 * structs (every field the def mirrors, compared bit for bit through mpm_scene_parse, which sees
 * the defaults no particle shows, and through mpm_scene_from_def, the tree the simulation is
 * made of) and the same simulation (count, positions, velocities and
 * masses, bit for bit, after creation and after one frame). */
#ifndef MPM_TEST_SCENE_DEF_SUPPORT_H
#define MPM_TEST_SCENE_DEF_SUPPORT_H

#include "support.h"
#include "mpm/mpm.h"
#include "scene/scene.h"

#include <stdio.h>
#include <string.h>

#define SAME(a, b, f) assert_memory_equal(&(a)->f, &(b)->f, sizeof(a)->f)

static inline void assert_same_shape(const mpm_shape_desc *a, const mpm_shape_desc *b) {
  SAME(a, b, kind);
  SAME(a, b, center);
  SAME(a, b, half_extent);
  SAME(a, b, radius);
  SAME(a, b, axis);
  SAME(a, b, half_height);
  SAME(a, b, mesh_scale);
  assert_string_equal(a->mesh_path, b->mesh_path);
  assert_int_equal(a->profile_count, b->profile_count);
  assert_memory_equal(a->profile, b->profile, (size_t)a->profile_count * sizeof a->profile[0]);
}

/* A collider's or a force region's motion, window and shape. */
static inline void assert_same_collider(const mpm_collider_desc *p, const mpm_collider_desc *q) {
  assert_string_equal(p->name, q->name);
  assert_same_shape(&p->shape, &q->shape);
  SAME(p, q, inside_out);
  SAME(p, q, rule);
  SAME(p, q, friction);
  SAME(p, q, motion.velocity);
  SAME(p, q, motion.axis);
  SAME(p, q, motion.angular_speed);
  assert_int_equal(p->motion.keyframe_count, q->motion.keyframe_count);
  for (int k = 0; k < p->motion.keyframe_count; ++k) {
    SAME(p, q, motion.keyframes[k].time);
    SAME(p, q, motion.keyframes[k].translation);
    SAME(p, q, motion.keyframes[k].angle);
  }
  SAME(p, q, active);
  SAME(p, q, heat_source);
  SAME(p, q, temperature);
}

static inline void assert_same_grid(const mpm_scene *a, const mpm_scene *b) {
  SAME(a, b, levels);
  SAME(a, b, refine_every);
  assert_int_equal(a->refine_count, b->refine_count);
  for (int k = 0; k < a->refine_count; ++k) {
    const mpm_refine_desc *p = &a->refine[k], *q = &b->refine[k];
    SAME(p, q, kind);
    SAME(p, q, level);
    SAME(p, q, min);
    SAME(p, q, max);
    SAME(p, q, collider);
    SAME(p, q, body);
    SAME(p, q, distance);
    SAME(p, q, strain);
  }
  const mpm_resample_desc *p = &a->resample, *q = &b->resample;
  SAME(p, q, enabled);
  SAME(p, q, split);
  SAME(p, q, merge);
  SAME(p, q, every);
  SAME(p, q, merge_margin);
  SAME(p, q, max_per_cell);
  SAME(p, q, min_per_cell);
  SAME(p, q, seed);
}

static inline void assert_same_output(const mpm_output_desc *a, const mpm_output_desc *b) {
  assert_string_equal(a->directory, b->directory);
  SAME(a, b, vtu);
  SAME(a, b, ply);
  SAME(a, b, stats);
  SAME(a, b, checkpoint_every);
  SAME(a, b, fields);
  const mpm_surface_desc *p = &a->surface, *q = &b->surface;
  SAME(p, q, enabled);
  assert_int_equal(p->body_count, q->body_count);
  assert_memory_equal(p->bodies, q->bodies, (size_t)p->body_count * sizeof p->bodies[0]);
  assert_int_equal(p->material_count, q->material_count);
  assert_memory_equal(p->materials, q->materials, (size_t)p->material_count * sizeof(int));
  SAME(p, q, voxel);
  SAME(p, q, radius);
  SAME(p, q, smoothing);
  SAME(p, q, filter);
  SAME(p, q, per_body);
  SAME(a, b, vdb);
  SAME(a, b, vdb_density);
  SAME(a, b, vdb_velocity);
}

static inline void assert_same_material(const mpm_material_desc *p, const mpm_material_desc *q) {
  assert_string_equal(p->name, q->name);
  SAME(p, q, model);
  SAME(p, q, E);
  SAME(p, q, nu);
  SAME(p, q, density);
  SAME(p, q, min_stretch);
  SAME(p, q, friction_angle);
  SAME(p, q, cohesion);
  SAME(p, q, yield_stress);
  SAME(p, q, theta_c);
  SAME(p, q, theta_s);
  SAME(p, q, hardening);
  assert_int_equal(p->strength_count, q->strength_count);
  assert_memory_equal(p->strength, q->strength, (size_t)p->strength_count * sizeof p->strength[0]);
  SAME(p, q, specific_heat);
  SAME(p, q, conductivity);
  SAME(p, q, melting);
  SAME(p, q, melt_point);
  SAME(p, q, melt_range);
  SAME(p, q, melt_shear);
  SAME(p, q, melt_bulk);
}

static inline void assert_same_body(const mpm_body_desc *p, const mpm_body_desc *q) {
  assert_string_equal(p->name, q->name);
  assert_same_shape(&p->shape, &q->shape);
  SAME(p, q, material);
  SAME(p, q, velocity);
  SAME(p, q, angular_velocity);
  SAME(p, q, particles_per_cell);
  SAME(p, q, jitter);
  SAME(p, q, seed);
  SAME(p, q, domains);
  SAME(p, q, enrichment);
  SAME(p, q, enrichment_exit);
  SAME(p, q, enrichment_metric);
  assert_int_equal(p->release_count, q->release_count);
  for (int k = 0; k < p->release_count; ++k) {
    SAME(p, q, release[k].time);
    SAME(p, q, release[k].min);
    SAME(p, q, release[k].max);
  }
  SAME(p, q, resample);
  SAME(p, q, has_temperature);
  SAME(p, q, temperature);
}

/* Every field of a scene that the def mirrors. */
static inline void assert_same_scene(const mpm_scene *a, const mpm_scene *b) {
  assert_string_equal(a->name, b->name);
  SAME(a, b, box_min);
  SAME(a, b, box_max);
  SAME(a, b, dx);
  assert_same_grid(a, b);
  SAME(a, b, gravity);
  SAME(a, b, wall_rule);
  SAME(a, b, wall_friction);
  SAME(a, b, wall_cells);
  SAME(a, b, end_time);
  SAME(a, b, fps);
  /* the solver desc is written field by field into a zeroed scene: its padding is zero too */
  SAME(a, b, solver);
  assert_same_output(&a->output, &b->output);
  SAME(a, b, camera.set);
  SAME(a, b, camera.eye);
  SAME(a, b, camera.target);
  SAME(a, b, camera.fov);
  SAME(a, b, heat.enabled);
  SAME(a, b, heat.temperature);
  SAME(a, b, heat.pic);
  assert_int_equal(a->material_count, b->material_count);
  for (int i = 0; i < a->material_count; ++i)
    assert_same_material(&a->materials[i], &b->materials[i]);
  assert_int_equal(a->body_count, b->body_count);
  for (int i = 0; i < a->body_count; ++i) assert_same_body(&a->bodies[i], &b->bodies[i]);
  assert_int_equal(a->collider_count, b->collider_count);
  for (int i = 0; i < a->collider_count; ++i)
    assert_same_collider(&a->colliders[i], &b->colliders[i]);
  assert_int_equal(a->force_count, b->force_count);
  for (int i = 0; i < a->force_count; ++i) {
    const mpm_force_desc *p = &a->forces[i], *q = &b->forces[i];
    assert_same_collider(&p->region, &q->region);
    SAME(p, q, acceleration);
    assert_int_equal(p->schedule_count, q->schedule_count);
    assert_memory_equal(p->schedule, q->schedule,
                        (size_t)p->schedule_count * sizeof p->schedule[0]);
  }
}

static inline void assert_same_view(const mpm_sim *a, const mpm_sim *b) {
  const mpm_particle_view va = mpm_sim_particles(a), vb = mpm_sim_particles(b);
  assert_true(va.count > 0);
  assert_int_equal(va.count, vb.count);
  const size_t n = va.count * va.real_size;
  for (int d = 0; d < 3; ++d) {
    assert_memory_equal(va.x[d], vb.x[d], n);
    assert_memory_equal(va.v[d], vb.v[d], n);
  }
  assert_memory_equal(va.mass, vb.mass, n);
  assert_memory_equal(va.material, vb.material, va.count * sizeof *va.material);
  assert_memory_equal(va.body, vb.body, va.count * sizeof *va.body);
}

/* The def and the JSON text make the same scene and the same simulation, before and after one
 * frame; base_dir resolves mesh files for both. */
static inline void assert_def_is_json(const mpm_scene_def *def, const char *json,
                                      const char *base_dir) {
  char err[2048];
  /* the scenes: the def's text (mesh paths resolve against the same folder) and the JSON */
  char *text = NULL;
  if (mpm_scene_def_to_json(def, &text, err, sizeof err) != MPM_OK) fail_msg("to_json: %s", err);
  char path[1100];
  snprintf(path, sizeof path, "%s/<def>", base_dir ? base_dir : ".");
  mpm_scene sa, sb, sc;
  mpm_error e;
  if (mpm_scene_parse(text, path, &sa, &e) != MPM_OK) fail_msg("the def's JSON: %s", e.message);
  if (mpm_scene_parse(json, path, &sb, &e) != MPM_OK) fail_msg("the JSON: %s", e.message);
  assert_same_scene(&sa, &sb);
  /* and the scene the simulation is made of: the def's tree, never printed and parsed */
  if (mpm_scene_from_def(def, base_dir, &sc, NULL, &e) != MPM_OK)
    fail_msg("the def: %s", e.message);
  assert_same_scene(&sc, &sb);
  assert_true(sc.source_hash != 0);
  mpm_scene_free(&sa);
  mpm_scene_free(&sb);
  mpm_scene_free(&sc);
  mpm_free_string(text);
  /* the simulations */
  mpm_sim *a = NULL, *b = NULL;
  if (mpm_sim_create_from_def(def, base_dir, &a, err, sizeof err) != MPM_OK)
    fail_msg("from the def: %s", err);
  if (mpm_sim_create_from_json(json, base_dir, &b, err, sizeof err) != MPM_OK)
    fail_msg("from the JSON: %s", err);
  assert_int_equal(mpm_sim_frame_count(a), mpm_sim_frame_count(b));
  assert_same_view(a, b);
  assert_int_equal(mpm_sim_advance_frame(a), MPM_OK);
  assert_int_equal(mpm_sim_advance_frame(b), MPM_OK);
  assert_int_equal(mpm_sim_steps(a), mpm_sim_steps(b));
  assert_true(mpm_sim_steps(a) > 0);
  assert_same_view(a, b);
  print_message("%zu particles, %lld steps in the first frame: the same\n",
                mpm_sim_particle_count(a), (long long)mpm_sim_steps(a));
  mpm_sim_destroy(a);
  mpm_sim_destroy(b);
}

/* Refused by create and by to_json alike, MPM_ERR_INVALID, with `field` in the message. A field
 * with ": expected" is the parser's check, which to_json does not run. */
static inline void assert_refused(const mpm_scene_def *def, const char *field) {
  char err[2048] = "";
  mpm_sim *sim = (mpm_sim *)&err; /* not NULL, to see it set to NULL */
  assert_int_equal(mpm_sim_create_from_def(def, NULL, &sim, err, sizeof err), MPM_ERR_INVALID);
  assert_null(sim);
  print_message("%s\n", err);
  if (!strstr(err, field)) fail_msg("'%s' does not name %s", err, field);
  assert_non_null(strstr(err, "<def>: "));
  char *text = (char *)err;
  err[0] = '\0';
  const mpm_status st = mpm_scene_def_to_json(def, &text, err, sizeof err);
  if (strstr(field, ": expected")) {
    if (st == MPM_OK) mpm_free_string(text);
    return;
  }
  assert_int_equal(st, MPM_ERR_INVALID);
  assert_null(text);
  if (!strstr(err, field)) fail_msg("to_json: '%s' does not name %s", err, field);
}

/* Written by to_json, refused by the format's check (create), naming `field`. */
static inline void assert_format_refuses(const mpm_scene_def *def, const char *field) {
  char err[2048] = "", *text = NULL;
  assert_int_equal(mpm_scene_def_to_json(def, &text, err, sizeof err), MPM_OK);
  mpm_free_string(text);
  mpm_sim *sim = (mpm_sim *)&err;
  assert_int_equal(mpm_sim_create_from_def(def, NULL, &sim, err, sizeof err), MPM_ERR_INVALID);
  assert_null(sim);
  print_message("%s\n", err);
  if (!strstr(err, field)) fail_msg("'%s' does not name %s", err, field);
  assert_non_null(strstr(err, "<def>: "));
}

#endif
