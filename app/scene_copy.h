/* scene_copy.h - keep the run's scene in its output folder (scene_copy.c). */
#ifndef MPM_APP_SCENE_COPY_H
#define MPM_APP_SCENE_COPY_H

#include "scene/scene.h"

/* Write dir/scene.json: the scene file's JSON with mesh paths made absolute. */
mpm_status mpm_write_scene_copy(const char *scene_path, const mpm_scene *scene, const char *dir,
                                mpm_error *err);

#endif
