/* scene_copy.c - the scene a run was made from, kept in its output folder as scene.json, so
 * that tools reading the folder later (`mpm render`) know the domain and the colliders. Mesh
 * files are referred to by absolute path in the copy, since the copy lives elsewhere. */
#define _DEFAULT_SOURCE /* realpath */
#include "scene_copy.h"
#include "io/io.h"

#include <cjson/cJSON.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *read_text(const char *path) {
  FILE *fp = fopen(path, "rb");
  if (!fp) return NULL;
  char *text = NULL;
  if (fseek(fp, 0, SEEK_END) == 0) {
    const long n = ftell(fp);
    if (n >= 0 && fseek(fp, 0, SEEK_SET) == 0 && (text = malloc((size_t)n + 1))) {
      if (fread(text, 1, (size_t)n, fp) != (size_t)n) {
        free(text);
        text = NULL;
      } else {
        text[n] = 0;
      }
    }
  }
  fclose(fp);
  return text;
}

mpm_status mpm_write_scene_copy(const char *scene_path, const mpm_scene *scene, const char *dir,
                                mpm_error *err) {
  char *text = read_text(scene_path);
  cJSON *root = text ? cJSON_Parse(text) : NULL;
  free(text);
  if (!root) return mpm_error_set(err, MPM_ERR_IO, "%s: cannot re-read the scene", scene_path);
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
  char *out = cJSON_Print(root);
  cJSON_Delete(root);
  if (!out) return mpm_error_set(err, MPM_ERR_NOMEM, "out of memory copying the scene");
  char path[MPM_PATH_MAX + 16];
  snprintf(path, sizeof path, "%s/scene.json", dir);
  mpm_atomic_file f;
  mpm_status st = mpm_atomic_open(&f, path, err);
  if (st == MPM_OK) {
    if (fputs(out, f.fp) < 0 || fputc('\n', f.fp) < 0) {
      mpm_atomic_abort(&f);
      st = mpm_error_set(err, MPM_ERR_IO, "%s: write failed", path);
    } else {
      st = mpm_atomic_commit(&f, err);
    }
  }
  free(out);
  return st;
}
