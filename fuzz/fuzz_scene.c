/* fuzz_scene.c - libFuzzer target for the JSON scene parser (scene/scene_json*.c,
 * scene/json_check.c, scene/json_syntax.c).
 *
 * The input is copied into a NUL-terminated buffer (mpm_scene_parse reads a C string, as
 * mpm_scene_load hands it one) and parsed as if it were tests/corpus/fuzz.json, so that mesh
 * bodies ("file": "meshes/cube.obj") resolve to the small meshes of the test corpus and the
 * mesh checks (closedness, area, volume, placement) run too. Every allocation is released;
 * nothing is printed. Built by fuzz/CMakeLists.txt; `make fuzz` runs it. */
#include "scene/scene.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define SCENE_PATH MPM_SOURCE_DIR "/tests/corpus/fuzz.json"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = malloc(size + 1);
  if (!text) return 0;
  if (size) memcpy(text, data, size);
  text[size] = '\0';
  mpm_scene scene;
  mpm_error err;
  mpm_scene_parse(text, SCENE_PATH, &scene, &err);
  mpm_scene_free(&scene);
  free(text);
  return 0;
}
