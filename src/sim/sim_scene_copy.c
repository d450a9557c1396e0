/* sim_scene_copy.c - the scene a run was made from, kept in its output folder as scene.json, so
 * that tools reading the folder later (`mpm render`, `mpm plot`) know the domain and the
 * colliders. The copy is made when the simulation is created from a scene file, JSON text or a
 * def, with its numbers exact (a run of the copy is the same run) and mesh files referred to by
 * absolute path (the copy lives elsewhere, and the caller may change its working directory), and
 * written by mpm_sim_enable_output. */
#define _DEFAULT_SOURCE /* realpath */
#include "sim/sim.h"
#include "core/alloc.h"
#include "io/run_folder.h"
#include "scene/json_check.h"

#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char *mpm_scene_copy_tree(cJSON *root, const mpm_scene *scene) {
  if (!root) return NULL;
  const cJSON *bodies = cJSON_GetObjectItemCaseSensitive(root, "bodies");
  int i = 0;
  for (const cJSON *b = bodies ? bodies->child : NULL; b && i < scene->body_count;
       b = b->next, ++i) {
    cJSON *shape = cJSON_GetObjectItemCaseSensitive(b, "shape");
    const cJSON *type = cJSON_GetObjectItemCaseSensitive(shape, "type");
    if (!cJSON_IsString(type) || strcmp(type->valuestring, "mesh")) continue;
    char abs_path[PATH_MAX];
    if (!realpath(scene->bodies[i].shape.mesh_path, abs_path)) continue;
    cJSON_ReplaceItemInObjectCaseSensitive(shape, "file", cJSON_CreateString(abs_path));
  }
  char *printed = mpm_json_print_exact(root, 1);
  char *out = printed ? mpm_strdup(printed) : NULL; /* the simulation frees it with mpm_free() */
  cJSON_free(printed);
  return out;
}

char *mpm_scene_copy_text(const char *json_text, const mpm_scene *scene) {
  cJSON *root = json_text ? cJSON_Parse(json_text) : NULL;
  char *out = mpm_scene_copy_tree(root, scene);
  cJSON_Delete(root);
  return out;
}

mpm_status mpm_sim_write_scene_copy(mpm_sim *sim) {
  if (!sim->scene_copy) return MPM_OK; /* made from a scene struct: no JSON to keep */
  char path[MPM_PATH_MAX + 16];
  snprintf(path, sizeof path, "%s/scene.json", sim->out.dir);
  /* the scene run is that file itself (`mpm run out/scene.json -o out`): it is left as the
     user wrote it (renaming the copy over it would replace the user's file) */
  if (sim->scene.path[0] && mpm_same_file(path, sim->scene.path)) return MPM_OK;
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, &sim->error);
  if (st != MPM_OK) return st;
  if (fputs(sim->scene_copy, f.fp) < 0 || fputc('\n', f.fp) < 0) {
    mpm_atomic_abort(&f);
    return mpm_error_set(&sim->error, MPM_ERR_IO, "%s: write failed", path);
  }
  return mpm_atomic_commit(&f, &sim->error);
}
