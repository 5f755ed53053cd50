# asperity: build, examples, tests and benchmarks.
# Every target installs what it needs (gmsh via apt-get, the Python venv via pip).
#   make thick_cylinder          run the thick-cylinder example (gmsh -> solver -> plots)
#   make test                    all tests (Rust unit/integration tests + output checks)
#   make mesh GEO=geo/X.geo SIZE=0.5   mesh a .geo script into build/mesh/
#   make bench                   timings at ~10k, ~100k, ~1M unknowns, appended to BENCHMARKS.md

SHELL   := /bin/bash
CARGO   ?= cargo
VENV    := .venv
PYTHON  := $(VENV)/bin/python
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
BIN     := target/release/asperity
SIZE    ?= 1

.PHONY: all deps gmsh venv build test mesh bench examples thick_cylinder clean

all: build

## --- dependencies -----------------------------------------------------------
deps: gmsh venv

gmsh:
	@command -v gmsh >/dev/null || { echo "installing gmsh (apt-get)"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq gmsh >/dev/null; }
	@gmsh --version >/dev/null 2>&1

venv: $(VENV)/.installed

$(VENV)/.installed: pipelines/requirements.txt
	@command -v python3 >/dev/null || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq python3 python3-venv >/dev/null; }
	@python3 -m venv $(VENV) 2>/dev/null || { $(SUDO) apt-get install -y -qq python3-venv >/dev/null && python3 -m venv $(VENV); }
	$(VENV)/bin/pip install -q --disable-pip-version-check -r pipelines/requirements.txt
	@touch $@

build:
	$(CARGO) build --release

## --- meshing ------------------------------------------------------------------
mesh: gmsh
	@test -n "$(GEO)" || { echo "usage: make mesh GEO=geo/X.geo [SIZE=0.5]"; exit 2; }
	@mkdir -p build/mesh
	gmsh $(GEO) -2 -order 2 -setnumber Mesh.SecondOrderIncomplete 1 -format msh41 -clscale $(SIZE) -v 2 \
	  -o build/mesh/$(basename $(notdir $(GEO)))-$(SIZE).msh
	@echo "mesh: build/mesh/$(basename $(notdir $(GEO)))-$(SIZE).msh"

## --- examples -----------------------------------------------------------------
examples: thick_cylinder

thick_cylinder: deps build
	$(BIN) run pipelines/thick_cylinder.toml --out out/thick_cylinder
	$(PYTHON) pipelines/plot_fields.py out/thick_cylinder --case pipelines/thick_cylinder.toml
	@echo "results: out/thick_cylinder (results.pvd for ParaView, *.png, history.csv)"

## --- tests --------------------------------------------------------------------
test: deps
	$(CARGO) test --release
	$(CARGO) build --release
	$(BIN) run pipelines/thick_cylinder.toml --out build/test/thick_cylinder
	$(PYTHON) pipelines/check_output.py build/test/thick_cylinder

## --- benchmarks ---------------------------------------------------------------
bench: gmsh
	$(CARGO) bench --bench elastic

clean:
	rm -rf target build out $(VENV)
