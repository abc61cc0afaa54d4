# Two entry points, each doing the whole set-up on a fresh Debian 12 machine:
#   make run   install what is missing, build, run the default scene, compare with theory
#   make test  the same set-up, then every test (CTest for C, pytest for Python)
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
        python3-yaml python3-pytest python3-matplotlib python3-scipy cython3 python3-dev \
        libopenblas0-serial

.PHONY: all deps build run test test-c test-python clean
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

test: build
	cd $(BUILD) && ctest --output-on-failure
	$(PYTHON) -m pytest -q tests/python

clean:
	rm -rf $(BUILD)
