# Two entry points, each doing the whole set-up on a fresh Debian 12 machine:
#   make run   install what is missing, build, run the default scene, compare with theory
#   make test  the same set-up, then every test (CTest for C, pytest for Python; pytest runs a
#              worker per core, each test file on one worker so its module fixtures are built once)
SHELL      := /bin/bash
BUILD      ?= build
PYTHON     := /usr/bin/python3
JOBS       ?= $(shell nproc)
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export PYTHONPATH := $(CURDIR)/python:$(CURDIR)/$(BUILD)/python$(if $(PYTHONPATH),:$(PYTHONPATH))
export MBC_BUILD_DIR := $(CURDIR)/$(BUILD)

DEBS := build-essential cmake pkg-config petsc-dev python3-petsc4py libmetis-dev gmsh \
        libhdf5-openmpi-dev openmpi-bin python3-meshio python3-h5py python3-numpy \
        python3-yaml python3-pytest python3-matplotlib python3-scipy cython3 python3-dev python3-mpi4py python3-venv python3-pytest-xdist \
        libopenblas0-serial slepc-dev python3-slepc4py

.PHONY: all deps build run test test-c test-python fuzz sanitize clean vtk-reader
all: build

# Installs only the Debian packages that are missing (idempotent; quiet when all are there).
deps:
	@missing=$$(for p in $(DEBS); do dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "Installing: $$missing"; \
	  SUDO=$$( [ $$(id -u) -eq 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq --no-install-recommends $$missing; \
	fi

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
	@cmake --build $(BUILD) -j $(JOBS)

run: build
	$(PYTHON) meshes/hertz/run.py

test: build vtk-reader
	cd $(BUILD) && ctest --output-on-failure
	$(PYTHON) -m pytest -q -n $(JOBS) --dist loadfile --durations=20 tests/python

# VTK's vtkXdmfReader (what ParaView reads .xmf with) for test_output.py: Debian 12's python3-vtk9
# lacks it, PyPI's vtk has it; a venv in the build directory, made once.
vtk-reader:
	@$(BUILD)/venv-vtk/bin/python -c 'import vtkmodules.vtkIOXdmf2' 2>/dev/null || \
	  { $(PYTHON) -m venv $(BUILD)/venv-vtk && $(BUILD)/venv-vtk/bin/pip install -q vtk; } || \
	  echo "warning: no vtk from PyPI: test_output.py's vtkXdmfReader test is skipped"

# Long fuzzing run (tests/fuzz/fuzz.py): make fuzz N=10000 SEED=1 (N mutants of each kind).
N    ?= 1000
SEED ?= 1
fuzz: build
	$(PYTHON) tests/fuzz/fuzz.py -n $(N) --seed $(SEED) -j $(JOBS)

# ASan + UBSan build in build-asan: the C tests and the fast Python tests of bad input run on it.
# Leak reports are off: MPI and PETSc keep their memory until exit.
SAN_ENV := ASAN_OPTIONS=detect_leaks=0:abort_on_error=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 MBC_BUILD_DIR=$(CURDIR)/build-asan
sanitize: deps
	@cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DMBC_SANITIZE=ON > /dev/null
	@cmake --build build-asan -j $(JOBS)
	cd build-asan && $(SAN_ENV) ctest --output-on-failure
	$(SAN_ENV) $(PYTHON) -m pytest -q tests/python/test_errors.py tests/python/test_fuzz.py

clean:
	rm -rf $(BUILD) build-asan
