/* cells_vtu.h - the multi-level grid's leaves as a VTK file (grid_cells.vtu, for ParaView and
 * `mpm render --grid`). */
#ifndef MPM_ADAPTIVE_CELLS_VTU_H
#define MPM_ADAPTIVE_CELLS_VTU_H

#include "adaptive/refinement.h"
#include "core/error.h"

/* The leaves of a multi-level grid finer than level 0, as voxels with CellData `level`,
 * written atomically (io/io.h's rule). */
mpm_status mpm_write_cells_vtu(const char *path, const mpm_refinement *r, double time,
                               mpm_error *err);

#endif
