/* limits.h - the fixed sizes of names and paths that descriptors and files share. */
#ifndef MPM_CORE_LIMITS_H
#define MPM_CORE_LIMITS_H

#define MPM_NAME_MAX 64
#define MPM_PATH_MAX 1024

#endif
