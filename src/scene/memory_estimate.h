/* memory_estimate.h - the memory a scene will need, and the check made before anything of it
 * is allocated (memory_estimate.c). */
#ifndef MPM_SCENE_MEMORY_ESTIMATE_H
#define MPM_SCENE_MEMORY_ESTIMATE_H

#include "core/error.h"
#include "scene/scene.h"

/* The bytes a scene will need (its expected particle count in
 * *particles when not NULL), the memory this process may use (MPM_MEMORY_LIMIT, else the
 * machine's available memory), and the check mpm_sim_create_from_scene makes before it
 * allocates anything: MPM_ERR_INVALID with the estimate when the scene does not fit. */
double mpm_scene_memory_estimate(const mpm_scene *scene, double *particles);
double mpm_available_memory(void);
mpm_status mpm_scene_check_memory(const mpm_scene *scene, mpm_error *err);
/* The bytes for `particles` particles of the scene, and the check for that many (the
 * multi-level grid's count from its tree). */
double mpm_scene_memory_for(const mpm_scene *scene, double particles);
mpm_status mpm_scene_check_memory_for(const mpm_scene *scene, double particles, mpm_error *err);

#endif
