# Thin front over CMake: `make demo` and `make test` do all the set-up on a fresh machine.
JOBS ?= 2
BUILD ?= build
BUILD_DOUBLE ?= build-double
BUILD_SANITIZE ?= build-sanitize
BUILD_FUZZ ?= build-fuzz
BUILD_TSAN ?= build-tsan
# make install: its own build tree, for a portable CPU (-march=$(MPM_INSTALL_ARCH)) rather than
# the build machine's (the other builds use -march=native); MPM_INSTALL_ARCH=native for that
BUILD_INSTALL ?= build-install
PREFIX ?= /usr/local
MPM_INSTALL_ARCH ?= x86-64-v2
FUZZ_SECONDS ?= 60
DEMO_SCENE ?= examples/jello_cubes.json
CMAKE_FLAGS ?=
# CI builds (CI set, as .ci/run's environment has it) treat every compiler warning as an error
ifneq ($(CI),)
CMAKE_FLAGS += -DMPM_WERROR=ON
endif

DEB_PACKAGES = cmake pkg-config libcjson-dev libcmocka-dev liblapacke-dev libpng-dev zlib1g-dev \
	libhdf5-dev gnuplot-nox python3-vtk9 valgrind libopenvdb-dev libboost-dev \
	python3-dev python3-numpy python3-pytest clang-format
# clang and its runtime (libFuzzer, sanitizers): only `make fuzz` and `make test-fuzz` need them
FUZZ_DEB_PACKAGES = clang libclang-rt-14-dev
# Blender (3.4, headless) for the add-on's test: `make test` installs it, `make demo` does not
BLENDER_DEB_PACKAGES = blender
# MPI (OpenMPI) for the distributed run's build and tests: `make test` installs it
MPI_DEB_PACKAGES = libopenmpi-dev openmpi-bin
# ThreadSanitizer needs clang and LLVM's OpenMP runtime with its Archer tool (libarcher.so)
TSAN_DEB_PACKAGES = clang libclang-rt-14-dev libomp-14-dev
ARCHER ?= /usr/lib/llvm-14/lib/libarcher.so
# the tests run under ThreadSanitizer: every parallel kernel (P2G colouring, G2P, the sort, the
# DOF set's reductions and update, the embedding's scatter, the transfer operators, domains)
TSAN_TESTS = test_sim|test_tile_batches|test_enrich_contact|test_enrich_surface_contact|test_resample_sim|test_domain_sim|test_domain|test_domain_apic|test_dofs|test_embedding|test_adaptive_grid|test_adaptive_step|test_transfer_operators|test_memory|test_cg|test_implicit|test_multigrid

.PHONY: all deps vdb-shim build build-double build-sanitize demo test test-float test-double \
	test-sanitize bench clean format valgrind deps-fuzz build-fuzz fuzz test-fuzz deps-tsan \
	build-tsan test-tsan install build-install deps-blender build-x86-64 test-x86-64 \
	deps-mpi build-mpi test-mpi

all: build

# Install the Debian packages of $(1) that are missing (root, or through sudo).
define apt_install
	@missing=""; for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing:$$missing"; \
	  if [ "$$(id -u)" != 0 ]; then SUDO=sudo; fi; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi
endef

# The packages the build needs; the fuzzing tool chain only for the fuzz targets.
deps:
	$(call apt_install,$(DEB_PACKAGES))

deps-fuzz: deps
	$(call apt_install,$(FUZZ_DEB_PACKAGES))

deps-tsan: deps
	$(call apt_install,$(TSAN_DEB_PACKAGES))

deps-blender: deps
	$(call apt_install,$(BLENDER_DEB_PACKAGES))

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD) -j $(JOBS)

# The OpenVDB shim (the module libmpmvdb.so, src/surface/vdb_shim.cpp) is the same for every
# precision and takes longer to compile than the rest of the library: it is built once, in
# $(BUILD), and the double and sanitizer builds load that one (CMakeLists.txt:
# MPM_VDB_SHIM_LIBRARY).
VDB_SHIM = $(abspath $(BUILD))/libmpmvdb.so
vdb-shim: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD) -j $(JOBS) --target mpmvdb

# (with libmpm.so, so that the Python module's tests run on the double build too: its arrays
# are float64 there)
build-double: vdb-shim
	cmake -S . -B $(BUILD_DOUBLE) -DCMAKE_BUILD_TYPE=Release -DMPM_DOUBLE=ON -DMPM_SHARED=ON \
	  -DMPM_VDB_SHIM_LIBRARY=$(VDB_SHIM) $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_DOUBLE) -j $(JOBS)

# AddressSanitizer + UndefinedBehaviorSanitizer build of the library and tests (the OpenVDB shim
# linked from $(BUILD), not instrumented: its own code is a thin wrapper, the rest is OpenVDB)
build-sanitize: vdb-shim
	cmake -S . -B $(BUILD_SANITIZE) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMPM_SANITIZE=ON \
	  -DMPM_VDB_SHIM_LIBRARY=$(VDB_SHIM) $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_SANITIZE) -j $(JOBS)

# libFuzzer targets (fuzz/): clang, ASan + UBSan + coverage, no OpenMP, no tests
build-fuzz: deps-fuzz
	cmake -S . -B $(BUILD_FUZZ) -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=Debug -DMPM_FUZZ=ON \
	  -DMPM_OPENMP=OFF -DMPM_OPENVDB=OFF -DBUILD_TESTING=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_FUZZ) -j $(JOBS) --target fuzz_scene fuzz_obj fuzz_ply fuzz_checkpoint

# ThreadSanitizer build (clang, LLVM's OpenMP) of the library and the tests of TSAN_TESTS
build-tsan: deps-tsan
	cmake -S . -B $(BUILD_TSAN) -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMPM_TSAN=ON -DMPM_OPENVDB=OFF \
	  $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_TSAN) -j $(JOBS) --target $(subst |, ,$(TSAN_TESTS))

# The libraries (libmpm.so, libmpm.a), mpm/mpm.h, mpm.pc, the CMake package and the program
# under $(PREFIX) (README "Using mpm as a library"); run as a user who may write there.
build-install: deps
	cmake -S . -B $(BUILD_INSTALL) -DCMAKE_BUILD_TYPE=Release -DMPM_ARCH=$(MPM_INSTALL_ARCH) \
	  -DCMAKE_INSTALL_PREFIX=$(PREFIX) -DBUILD_TESTING=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_INSTALL) -j $(JOBS)

install: build-install
	cmake --install $(BUILD_INSTALL) --prefix $(PREFIX)

# Only the program the demo runs (the test programs are `make test`'s): a fresh clone's demo
# builds in about a minute.
demo: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD) -j $(JOBS) --target mpm
	./$(BUILD)/mpm run $(DEMO_SCENE) -o out --overwrite

# The whole suite: the default float build, the double build, float under ASan + UBSan, the
# parallel tests under ThreadSanitizer, a short fuzz run of the scene, mesh and checkpoint
# readers, and the valgrind run below.
test: test-float test-double test-sanitize test-tsan test-x86-64 test-mpi test-fuzz valgrind

test-float: build deps-blender
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The malformed-input corpus is left to the float and sanitizer builds (DOUBLE_SKIP): its 400
# runs of the program are input checks that the real type does not reach, and each run's start
# costs about 55 ms (42 ms of it loading OpenVDB's libraries), 22 s in all. The Blender add-on
# reads the files, not the engine: the float build's run checks it. The tree's own checks
# (shape_check, format_check) run once, in the float build.
DOUBLE_SKIP = test_corpus|blender_addon|shape_check|format_check
test-double: build-double
	cd $(BUILD_DOUBLE) && ctest --output-on-failure -j $(JOBS) -E '^($(DOUBLE_SKIP))$$'

# Three long physics runs are left to the float and double builds (SANITIZE_SKIP): under ASan
# they were 40% of the suite's time (test_implicit_balance alone 223 s of the sanitizer run's
# 382), and every code path they take (the example scenes' steps, Drucker-Prager on the sparse
# grid, the implicit step's Newton and CG with both preconditioners) runs under ASan in
# test_sim, test_domain_sim, test_plasticity, test_implicit, test_multigrid and the others. So is VTK's reading of the files
# (vtk_reader_check, a check of the file formats, 28 s under ASan): the writers' code runs under
# ASan in test_outputs, test_io, test_output_fields and test_cli. The Blender add-on likewise
# (the float build checks it), and the tree's own checks.
SANITIZE_SKIP = test_regression|test_sand_pile|test_implicit_balance|vtk_reader_check|adversary_campaign|blender_addon|shape_check|format_check
test-sanitize: build-sanitize
	cd $(BUILD_SANITIZE) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	  ctest --output-on-failure -j $(JOBS) -E '^($(SANITIZE_SKIP))$$'

# Archer (OMP_TOOL_LIBRARIES) tells ThreadSanitizer about OpenMP's barriers and locks; any
# report fails the run.
test-tsan: build-tsan
	cd $(BUILD_TSAN) && OMP_TOOL_LIBRARIES=$(ARCHER) TSAN_OPTIONS="halt_on_error=1 exitcode=66 ignore_noninstrumented_modules=1" \
	  ctest --output-on-failure -j $(JOBS) -R '^($(TSAN_TESTS))$$'

# Fuzz the scene parser, the OBJ and PLY readers and the checkpoint reader for FUZZ_SECONDS each (fuzz/run.sh):
# executions per target are printed; a crash, leak, sanitizer report or timeout fails, with
# the input under $(BUILD_FUZZ)/artifacts/. The working corpus is $(BUILD_FUZZ)/corpus/.
fuzz: build-fuzz
	fuzz/run.sh $(BUILD_FUZZ) $(FUZZ_SECONDS)

test-fuzz: build-fuzz
	fuzz/run.sh $(BUILD_FUZZ) 15

# The distributed run's build (-DMPM_MPI=ON: src/dist/mpi_*.c on OpenMPI), float, without OpenVDB
# and the Python module, and its tests (tests/mpi: each program on 1 to 4 ranks, named _npN;
# the program itself for `mpm run` under mpirun, tests/mpi/run_cli.sh).
BUILD_MPI = build-mpi
deps-mpi: deps
	$(call apt_install,$(MPI_DEB_PACKAGES))

build-mpi: deps-mpi
	cmake -S . -B $(BUILD_MPI) -DCMAKE_BUILD_TYPE=Release -DMPM_MPI=ON -DMPM_OPENVDB=OFF \
	  -DMPM_PYTHON=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_MPI) -j $(JOBS) --target mpm \
	  $$(ls tests/mpi | sed -n 's/^\(test_[a-z_0-9]*\)\.c$$/\1/p')

test-mpi: build-mpi
	cd $(BUILD_MPI) && ctest --output-on-failure -j $(JOBS) -R '_np[0-9]+$$'

# A plain x86-64 build (-march=x86-64: SSE2, no AVX, no FMA), RelWithDebInfo, without OpenVDB
# and the Python module: the lanes, the SVD and the transfers compiled for the oldest x86-64 a
# user may have. The physics tests that check against tolerances (analytic solutions, finite
# differences, conservation, 1 vs 2 threads) run on it (X86_64_TESTS); the regression digests
# hold the native build's rounding (FMA) and are left out. valgrind runs the program from it.
BUILD_X86_64 = build-x86-64
X86_64_TESTS = test_svd|test_svd_lapack|test_kernel|test_material|test_plasticity|test_transfer_operators|test_implicit|test_cg|test_multigrid|test_dofs|test_embedding|test_domain|test_domain_apic|test_adaptive_grid|test_adaptive_step|test_refinement|test_resample|test_heat|test_sim|test_vecmath|test_mat3
build-x86-64: deps
	cmake -S . -B $(BUILD_X86_64) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMPM_ARCH=x86-64 \
	  -DMPM_OPENVDB=OFF -DMPM_PYTHON=OFF $(CMAKE_FLAGS) >/dev/null
	cmake --build $(BUILD_X86_64) -j $(JOBS) --target mpm $(subst |, ,$(X86_64_TESTS))

test-x86-64: build-x86-64
	cd $(BUILD_X86_64) && ctest --output-on-failure -j $(JOBS) -R '^($(X86_64_TESTS))$$'

# valgrind (Debian's valgrind) on a small scene with two materials (Drucker-Prager through the
# SIMD SVD, fixed-corotated), a revolve container and a sphere: one frame with a checkpoint,
# then resumed from it to the end and rendered: no invalid access and no leak, or the target
# fails. The plain x86-64 build: valgrind knows no AVX-512. Without OpenVDB: the tiny scene
# writes no particle surface. OMP_WAIT_POLICY set: without it the program runs itself again
# with the passive policy (app/main.c), which valgrind, not following the exec, did not check.
valgrind: build-x86-64
	rm -rf $(BUILD_X86_64)/out
	OMP_WAIT_POLICY=PASSIVE valgrind --error-exitcode=3 --leak-check=full --errors-for-leak-kinds=definite,indirect \
	  ./$(BUILD_X86_64)/mpm run tests/valgrind/tiny_scene.json -o $(BUILD_X86_64)/out --threads 1 \
	  --quiet --frames 1
	OMP_WAIT_POLICY=PASSIVE valgrind --error-exitcode=3 --leak-check=full --errors-for-leak-kinds=definite,indirect \
	  ./$(BUILD_X86_64)/mpm run tests/valgrind/tiny_scene.json --resume $(BUILD_X86_64)/out \
	  --threads 1 --quiet --render

bench: build
	./$(BUILD)/mpm bench step
	./$(BUILD)/mpm bench transfer

format:
	clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(BUILD_DOUBLE) $(BUILD_SANITIZE) $(BUILD_FUZZ) $(BUILD_TSAN) $(BUILD_INSTALL) \
	  $(BUILD_X86_64) out
