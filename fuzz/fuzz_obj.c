/* fuzz_obj.c - libFuzzer target for the OBJ reader of scene/mesh.c (mpm_mesh_parse with
 * MPM_MESH_OBJ), then bounds, open edges and the inside test on what it returns
 * (fuzz_mesh.h). Built by fuzz/CMakeLists.txt; `make fuzz` runs it. */
#include "fuzz_mesh.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  return mpm_fuzz_mesh(data, size, MPM_MESH_OBJ, "fuzz.obj");
}
