#!/bin/sh
# check.sh - ctest install_check: the installed library works from outside this project.
#
#   check.sh BUILD_DIR SOURCE_DIR CMAKE CC PKG_CONFIG
#
# Installs BUILD_DIR into a temporary prefix (cmake --install --prefix), then, as a program
# that knows nothing of this source tree:
#   1. the prefix holds the shared and the static library, the header, mpm.pc and the CMake
#      package, and libmpm.so's dynamic symbols are the public API only;
#   2. examples/embed.c builds through pkg-config, shared and static (--static), and runs, and
#      so does examples/embed_def.c (the scene built in code), shared;
#   3. a CMake project (consumer/) finds the package with find_package(mpm), builds embed.c
#      against mpm::mpm and against mpm::mpm_static, and runs both;
#   4. a CMake project that takes the source tree with add_subdirectory configures with the
#      libraries and without the tests and the program (configured only: building the library
#      again would double the test's time);
#   5. the Python package (when the build made it): Debian's python3 imports it from the
#      prefix's dist-packages, on the installed libmpm.so, and runs a step.
# Everything is made under one temporary folder, removed at the end whatever the outcome.
set -eu
build=$1 src=$2 cmake=$3 cc=$4 pkgconfig=$5

tmp=$(mktemp -d "${TMPDIR:-/tmp}/mpm-install-check.XXXXXX")
trap 'rm -rf "$tmp"' EXIT INT TERM
prefix=$tmp/prefix
fail() {
  echo "install_check: $*" >&2
  exit 1
}

echo "== install into $prefix"
"$cmake" --install "$build" --prefix "$prefix" >"$tmp/install.log" || {
  cat "$tmp/install.log"
  fail "cmake --install failed"
}
pc=$(find "$prefix" -name mpm.pc | head -n 1)
[ -n "$pc" ] || fail "no mpm.pc under $prefix"
libdir=$(dirname "$(dirname "$pc")")
for f in "$libdir/libmpm.so" "$libdir/libmpm.a" "$prefix/include/mpm/mpm.h" \
  "$prefix/share/mpm/blender/io_import_mpm_run/__init__.py" \
  "$prefix/include/mpm/scene_def.h" "$prefix/include/mpm/render.h" "$prefix/include/mpm/plot.h" \
  "$libdir/cmake/mpm/mpmConfig.cmake" "$libdir/cmake/mpm/mpmConfigVersion.cmake"; do
  [ -e "$f" ] || fail "$f was not installed"
done
# the shared library exports the functions of mpm.h and nothing else (OpenMP's named critical
# sections, .gomp_critical_user_*, are the runtime's, not ours)
nm -D --defined-only "$libdir/libmpm.so" | awk '{print $3}' | grep -v '^\.gomp_critical_user_' |
  sort >"$tmp/exported"
# (mpm.h includes scene_def.h, render.h and plot.h: the declarations of all are the public API)
cat "$prefix/include/mpm/mpm.h" "$prefix/include/mpm/scene_def.h" \
  "$prefix/include/mpm/render.h" "$prefix/include/mpm/plot.h" | grep -o 'mpm_[a-z_0-9]*(' |
  tr -d '(' | sort -u >"$tmp/declared"
extra=$(comm -23 "$tmp/exported" "$tmp/declared")
[ -z "$extra" ] || fail "libmpm.so exports symbols the public headers do not declare: $extra"
count=$(grep -c . "$tmp/exported")
echo "libmpm.so exports $count functions, all of them declared in the public headers"

echo "== pkg-config"
export PKG_CONFIG_PATH="$libdir/pkgconfig"
flags=$("$pkgconfig" --cflags --libs mpm) || fail "pkg-config --cflags --libs mpm failed"
echo "pkg-config --cflags --libs mpm: $flags"
# shellcheck disable=SC2086 # the flags are words
# no rpath of ours: mpm.pc's Libs carry it, so the program starts as built
"$cc" -Wall -Wextra -Werror -o "$tmp/embed_pc" "$src/examples/embed.c" $flags ||
  fail "embed.c does not build through pkg-config"
# it runs on the installed libmpm.so, not on the build tree's
# (the rpath mpm.pc gives is the relocatable libdir, pkgconfig/../../lib: compared resolved)
loaded=$(ldd "$tmp/embed_pc" | awk '/libmpm\.so/ {print $3}')
[ -n "$loaded" ] && [ "$(readlink -f "$loaded")" = "$(readlink -f "$libdir/libmpm.so")" ] ||
  fail "embed_pc does not load $libdir/libmpm.so (it loads '$loaded')"
(cd "$tmp" && ./embed_pc) || fail "embed_pc (pkg-config, shared) failed"
# the scene built in code, from the installed scene_def.h
# shellcheck disable=SC2086
"$cc" -Wall -Wextra -Werror -o "$tmp/embed_def_pc" "$src/examples/embed_def.c" $flags ||
  fail "embed_def.c does not build through pkg-config"
(cd "$tmp" && ./embed_def_pc) || fail "embed_def_pc (pkg-config, shared) failed"
# static: --static adds what libmpm.a needs; the archive is named, as the linker would take
# libmpm.so for -lmpm (mpm.pc says so)
static=$("$pkgconfig" --static --libs mpm | sed "s|-lmpm |$libdir/libmpm.a |")
echo "static: $static"
# shellcheck disable=SC2086
"$cc" -Wall -Wextra -Werror -o "$tmp/embed_pc_static" "$src/examples/embed.c" \
  $("$pkgconfig" --cflags mpm) $static || fail "embed.c does not link libmpm.a through pkg-config --static"
if ldd "$tmp/embed_pc_static" | grep -q libmpm.so; then
  fail "embed_pc_static loads libmpm.so"
fi
(cd "$tmp" && ./embed_pc_static) || fail "embed_pc_static (pkg-config --static) failed"

echo "== find_package(mpm)"
mkdir "$tmp/consumer"
cat >"$tmp/consumer/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.20)
project(consumer C)
find_package(mpm 0.3 REQUIRED)
message(STATUS "mpm \${mpm_VERSION}, \${mpm_REAL_TYPE} reals")
add_executable(embed_shared "$src/examples/embed.c")
target_link_libraries(embed_shared PRIVATE mpm::mpm)
add_executable(embed_static "$src/examples/embed.c")
target_link_libraries(embed_static PRIVATE mpm::mpm_static)
CMAKE
"$cmake" -S "$tmp/consumer" -B "$tmp/consumer/build" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_C_COMPILER="$cc" >"$tmp/consumer.log" 2>&1 || {
  cat "$tmp/consumer.log"
  fail "the CMake project does not configure with find_package(mpm)"
}
grep "mpm 0" "$tmp/consumer.log" || true
"$cmake" --build "$tmp/consumer/build" >"$tmp/consumer-build.log" 2>&1 || {
  cat "$tmp/consumer-build.log"
  fail "the CMake project does not build against mpm::mpm and mpm::mpm_static"
}
ldd "$tmp/consumer/build/embed_shared" | grep -q "$libdir/libmpm.so" ||
  fail "embed_shared does not load $libdir/libmpm.so"
if ldd "$tmp/consumer/build/embed_static" | grep -q libmpm.so; then
  fail "embed_static loads libmpm.so"
fi
(cd "$tmp" && "$tmp/consumer/build/embed_shared") || fail "embed_shared (find_package) failed"
(cd "$tmp" && "$tmp/consumer/build/embed_static") || fail "embed_static (find_package) failed"

if [ -d "$build/python/mpm" ]; then
  echo "== the Python package"
  ext=$(find "$prefix" -path '*dist-packages/mpm/_mpm*.so' | head -n 1)
  [ -n "$ext" ] || fail "the Python package was not installed (no dist-packages/mpm/_mpm*.so)"
  [ -e "$(dirname "$ext")/__init__.py" ] || fail "mpm/__init__.py was not installed"
  loaded=$(ldd "$ext" | awk '/libmpm\.so/ {print $3}')
  [ -n "$loaded" ] && [ "$(readlink -f "$loaded")" = "$(readlink -f "$libdir/libmpm.so")" ] ||
    fail "$ext does not load $libdir/libmpm.so (it loads '$loaded')"
  (cd "$tmp" && PYTHONPATH=$(dirname "$(dirname "$ext")") /usr/bin/python3 -c "
import mpm
sim = mpm.Simulation({'domain': {'min': [0, 0, 0], 'max': [0.2, 0.2, 0.2], 'dx': 0.02},
                      'time': {'end': 0.1, 'fps': 10},
                      'materials': [{'name': 'm', 'model': 'neo_hookean', 'E': 1e4, 'nu': 0.3,
                                     'density': 1000}],
                      'bodies': [{'shape': {'type': 'box', 'center': [0.1, 0.1, 0.1],
                                            'half_extent': [0.03, 0.03, 0.03]},
                                  'material': 'm'}]})
sim.step()
assert mpm.__file__.startswith('$prefix'), mpm.__file__
print('import mpm from', mpm.__file__, '-', len(sim.particles), 'particles, one step')
") || fail "the installed Python package does not import and step"
fi

echo "== add_subdirectory(mpm)"
mkdir "$tmp/parent"
cat >"$tmp/parent/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.20)
project(parent C)
add_subdirectory("$src" mpm)
foreach(t mpm::mpm mpm::mpm_static)
  if(NOT TARGET \${t})
    message(FATAL_ERROR "add_subdirectory(mpm) made no \${t}")
  endif()
endforeach()
foreach(t mpm test_sim test_public_api example_embed)
  if(TARGET \${t})
    message(FATAL_ERROR "add_subdirectory(mpm) made \${t}: only the libraries belong there")
  endif()
endforeach()
add_executable(embed "$src/examples/embed.c")
target_link_libraries(embed PRIVATE mpm::mpm)
CMAKE
"$cmake" -S "$tmp/parent" -B "$tmp/parent/build" -DCMAKE_C_COMPILER="$cc" \
  >"$tmp/parent.log" 2>&1 || {
  cat "$tmp/parent.log"
  fail "a project with add_subdirectory(mpm) does not configure"
}
echo "install_check: all passed"
