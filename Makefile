# asperity: build, examples, tests and benchmarks.
# Every target installs what it needs (gmsh via apt-get, the Python venv via pip).
#   make tapered_joint           the main example: conical press fit (paper §4.2) -> out/tapered_joint
#   make plane_punch             plane punch on a foundation (paper §4.1) -> out/plane_punch
#   make indentation             axisymmetric punch into an elasto-plastic foundation (§4.3)
#   make examples                all of the above and the validation examples
#   make thick_cylinder          Lamé thick cylinder (gmsh -> solver -> plots)
#   make prandtl                 Prandtl's punch on a perfectly plastic half-space (B-bar element)
#   make shrink_fit              shrink-fit contact example
#   make fretting                tapered joint pressed in, then 10^6 load cycles with wear -> out/fretting
#   make taper_torque            tapered joint seated, twisted until it slips, then torsional fretting -> out/taper_torque
#   make shrink_fit_thermal      shrink fit by heating the hub; make joint_thermal: heat through a joint
#   make test                    all tests (Rust unit/integration tests + output checks)
#   make convergence             mesh-convergence verification studies -> out/convergence
#   make mesh GEO=geo/X.geo SIZE=0.5   mesh a .geo script into build/mesh/
#   make bench                   timings at ~10k, ~100k, ~1M unknowns, appended to BENCHMARKS.md
#   make bench-scale             the ~1M-unknown frictional tapered press fit (part of make bench) -> BENCHMARKS.md
#   make bench-calculix          asperity against CalculiX 2.20 on the same meshes, increments and answers -> BENCHMARKS.md
#   make fuzz FUZZ_SECONDS=600   fuzz the MSH reader, the case parser and model building (cargo fuzz, nightly)
#   make example NAME=slideway   one example of the gallery (examples/<NAME>/README.md; `make example` lists them)
#   make reference               regenerate docs/guide/case-file.md from the case-file schema
#   make install PREFIX=/usr/local   the binary, its man pages and bash/zsh/fish completions

SHELL   := /bin/bash
CARGO   ?= cargo
VENV    := .venv
PYTHON  := $(VENV)/bin/python
SUDO    := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
BIN     := target/release/asperity
SIZE    ?= 1

.PHONY: all deps gmsh venv build test mesh bench examples tapered_joint plane_punch indentation thick_cylinder shrink_fit prandtl clean
.PHONY: convergence bench-calculix bench-scale
.PHONY: fit-example sweep-test gnu-parallel doc
.PHONY: fuzz
.PHONY: fretting
.PHONY: reference install install-test
.PHONY: example example-slideway example-shrink_fit example-tapered_joint example-fretting example-taper_torque example-fit example-sweep examples-test

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
examples: tapered_joint plane_punch indentation thick_cylinder shrink_fit prandtl

tapered_joint plane_punch indentation: deps build
	$(PYTHON) pipelines/$@.py --out out/$@
	@echo "results: out/$@ (REPORT.md, figures, one folder per run with results.pvd for ParaView)"

thick_cylinder: deps build
	$(BIN) run pipelines/thick_cylinder.toml --out out/thick_cylinder --force
	$(PYTHON) pipelines/plot_fields.py out/thick_cylinder --case pipelines/thick_cylinder.toml
	@echo "results: out/thick_cylinder (results.pvd for ParaView, *.png, history.csv)"

prandtl: deps build
	$(BIN) run pipelines/prandtl.toml --out out/prandtl --force
	$(PYTHON) pipelines/plot_fields.py out/prandtl --case pipelines/prandtl.toml
	@echo "results: out/prandtl (results.pvd for ParaView, *.png, history.csv: mean pressure = -reaction_top_y / 10 mm)"

shrink_fit: deps build
	$(BIN) run examples/shrink_fit/shrink_fit.toml --out out/shrink_fit --force
	$(PYTHON) pipelines/plot_fields.py out/shrink_fit --case examples/shrink_fit/shrink_fit.toml
	@echo "results: out/shrink_fit (results.pvd for ParaView, *.png, contact_fit_*.csv, history.csv)"

# `make fretting`: the case meshes its own .geo ([mesh] geo), runs the press-in and the cyclic
# step with wear, then report.py draws the figures (plot_hysteresis.py) and writes REPORT.md,
# and check_fretting.py checks the files against each other. Your own joint:
# make fretting FRETTING_CASE=my_case.toml [FRETTING_OUT=out/my_case]
FRETTING_CASE ?= examples/fretting/tapered_fretting.toml
FRETTING_OUT  ?= out/fretting
fretting: deps build
	$(BIN) run $(FRETTING_CASE) --out $(FRETTING_OUT) --force
	$(PYTHON) pipelines/fretting/report.py $(FRETTING_OUT)
	$(PYTHON) pipelines/fretting/check_fretting.py $(FRETTING_OUT) >$(FRETTING_OUT)/checks.txt \
	  || { cat $(FRETTING_OUT)/checks.txt; exit 1; }
	@echo "results: $(FRETTING_OUT) (REPORT.md, hysteresis_*.png, cycles.png, wear_*.png, checks.txt, results.pvd for ParaView)"

## --- tests --------------------------------------------------------------------
test: deps
	$(CARGO) test --release
	$(CARGO) build --release
	@for e in tapered_joint plane_punch indentation; do \
	  test -f pipelines/$$e.py || continue; \
	  echo "example $$e (coarse)"; \
	  $(PYTHON) pipelines/$$e.py --quick --out build/test/$$e || exit 1; \
	  for d in build/test/$$e/*/; do \
	    test -f $$d/results.pvd && { $(PYTHON) pipelines/check_output.py $$d >/dev/null || exit 1; }; \
	  done; \
	done
	@for c in pipelines/thick_cylinder examples/shrink_fit/shrink_fit examples/shrink_fit/shrink_fit_split; do \
	  n=$$(basename $$c); \
	  $(BIN) run $$c.toml --out build/test/$$n --force >/dev/null && \
	  $(PYTHON) pipelines/check_output.py build/test/$$n || exit 1; \
	  $(PYTHON) pipelines/plot_fields.py build/test/$$n >/dev/null 2>&1 || { echo "plot_fields.py failed on $$n"; exit 1; }; \
	done
	$(PYTHON) pipelines/fretting/selftest.py >/dev/null
	$(PYTHON) pipelines/fretting/check_fretting.py --quick build/test/fretting >build/test/fretting.txt || { cat build/test/fretting.txt; exit 1; }
	$(call convergence_studies,3,3,build/test/convergence,$(CONVERGENCE_SUMMARY))
	@$(MAKE) --no-print-directory sweep-test fit-example OUT_FIT=build/test/fit
	@$(MAKE) --no-print-directory examples-test install-test thermal-test

# `make doc`: the library's API documentation (target/doc/asperity), failing on a broken link.
doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --no-deps

## --- fitting and sweeps --------------------------------------------------------
# `make fit-example`: the README's worked example (examples/fit/joint.toml) -> out/fit/joint.
OUT_FIT ?= out/fit
fit-example sweep-test: export ASPERITY_PIPELINES := $(CURDIR)/pipelines
fit-example: venv build
	$(BIN) fit examples/fit/joint.toml --out $(OUT_FIT)/joint
	@test -s $(OUT_FIT)/joint/fit.png && test -s $(OUT_FIT)/joint/residuals.png || { echo "fit-example: plots missing"; exit 1; }

gnu-parallel:
	@command -v parallel >/dev/null || { echo "installing parallel (apt-get)"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq parallel >/dev/null; }

# `make sweep-test`: the specimen sweep (examples/sweep/specimen.toml) run by the local pool and
# by GNU parallel from jobs.txt must give identical tables; array.sbatch is checked for its
# array range, per-task command and resource lines.
SWEEP_TEST := build/test/sweep
sweep-test: gnu-parallel venv build
	@rm -rf $(SWEEP_TEST) && mkdir -p $(SWEEP_TEST)
	$(BIN) sweep plan examples/sweep/specimen.toml --out $(SWEEP_TEST)/local
	$(BIN) sweep plan examples/sweep/specimen.toml --out $(SWEEP_TEST)/parallel
	$(BIN) sweep run $(SWEEP_TEST)/local --jobs 2
	parallel --will-cite --jobs 2 --halt now,fail=1 < $(SWEEP_TEST)/parallel/jobs.txt >/dev/null
	$(BIN) sweep collect $(SWEEP_TEST)/local
	$(BIN) sweep collect $(SWEEP_TEST)/parallel --no-plot
	cmp $(SWEEP_TEST)/local/sweep.csv $(SWEEP_TEST)/parallel/sweep.csv
	@test -s $(SWEEP_TEST)/local/force.png || { echo "sweep-test: force.png missing"; exit 1; }
	@s=$(SWEEP_TEST)/parallel/array.sbatch; bash -n $$s && \
	  grep -qx '#SBATCH --array=0-5' $$s && grep -qx '#SBATCH --ntasks=1' $$s && \
	  grep -qx '#SBATCH --cpus-per-task=1' $$s && grep -qx '#SBATCH --mem=1G' $$s && \
	  grep -qx '#SBATCH --time=00:10:00' $$s && \
	  grep -q "sweep run '.*/$(SWEEP_TEST)/parallel' --task \"\$$SLURM_ARRAY_TASK_ID\"$$" $$s \
	  || { echo "sweep-test: $$s lacks the array range, resource lines or per-task command"; exit 1; }
	@echo "sweep-test: local pool and GNU parallel give identical tables; array.sbatch checked"

## --- convergence studies ------------------------------------------------------
# pipelines/convergence/*.toml (README "Convergence studies"): every study must pass, and the
# singular edge pressure of flat_punch_edge must be reported as not converged (exit status 1,
# status `not_converged` in its convergence.csv).
CONVERGENCE_STUDIES := thick_cylinder shrink_fit flat_punch tapered_joint
CONVERGENCE_SUMMARY := sed -n '/^summary:/,/^table:/p'

# $(call convergence_studies,LEVELS_CHEAP,LEVELS,OUT,SHOW): LEVELS_CHEAP levels for the cheap
# smooth studies (thick_cylinder, shrink_fit), LEVELS for the others; SHOW filters the tables.
define convergence_studies
	@mkdir -p $(3)
	@for s in $(CONVERGENCE_STUDIES); do \
	  levels=$(2); case $$s in thick_cylinder|shrink_fit) levels=$(1);; esac; \
	  echo "== convergence study $$s ($$levels levels, ratio 2)"; \
	  $(BIN) converge pipelines/convergence/$$s.toml --levels $$levels --out $(3)/$$s >$(3)/$$s.txt 2>&1 \
	    || { cat $(3)/$$s.txt; exit 1; }; \
	  $(4) $(3)/$$s.txt; \
	done
	@echo "== convergence study flat_punch_edge ($(2) levels): must be reported as not converged"
	@$(BIN) converge pipelines/convergence/flat_punch_edge.toml --levels $(2) --out $(3)/flat_punch_edge \
	  >$(3)/flat_punch_edge.txt 2>&1; status=$$?; $(4) $(3)/flat_punch_edge.txt; \
	  if [ $$status = 1 ] && grep -q "^edge_pressure,.*,not_converged$$" $(3)/flat_punch_edge/convergence.csv; then \
	    echo "   as expected: edge_pressure not converged, exit status 1"; \
	  else echo "flat_punch_edge: expected exit status 1 and 'not converged' (got $$status)"; exit 1; fi
endef

convergence: deps build
	$(call convergence_studies,5,4,out/convergence,cat)
	@echo "results: out/convergence/<study>/ (convergence.csv, convergence.png, level_k/)"

## --- benchmarks ---------------------------------------------------------------
bench: gmsh venv build
	$(CARGO) bench --bench elastic
	$(CARGO) bench --bench contact
	$(CARGO) bench --bench twist
	$(PYTHON) pipelines/compare_algorithms.py examples/tapered_joint/coulomb.toml examples/tapered_joint/compliant_1.toml examples/tapered_joint/compliant_2.toml
	$(MAKE) bench-scale

# ~1M-unknown frictional tapered press fit, 10 increments: breakdown + peak RSS -> BENCHMARKS.md
bench-scale: gmsh venv build
	nice -n 10 $(PYTHON) benches/bench_scale.py --write

# make bench-calculix QUICK=1: small meshes, agreement check in minutes, BENCHMARKS.md untouched
bench-calculix: gmsh venv build
	@command -v ccx >/dev/null || { echo "installing calculix-ccx (apt-get)"; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq calculix-ccx >/dev/null; }
	$(PYTHON) benches/calculix/bench_calculix.py $(if $(QUICK),--quick,--write)

## --- fuzzing ------------------------------------------------------------------
# make fuzz FUZZ_SECONDS=1200: each cargo-fuzz target of fuzz/ (MSH reader, case file, mesh ->
# model) for FUZZ_SECONDS, one after the other at the lowest priority, from seeds made by
# fuzz/seed.sh; crashes, hangs (> 10 s) and out-of-memory inputs land in fuzz/artifacts/<target>/.
FUZZ_SECONDS ?= 60
FUZZ_TARGETS := msh_reader case_file model_build
fuzz: gmsh
	@command -v cargo-fuzz >/dev/null || $(CARGO) install cargo-fuzz
	fuzz/seed.sh
	@for t in $(FUZZ_TARGETS); do \
	  echo "== fuzzing $$t for $(FUZZ_SECONDS) s"; \
	  (cd fuzz && nice -n 19 $(CARGO) +nightly fuzz run -O $$t corpus/$$t -- \
	    -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 -print_final_stats=1) || exit 1; \
	done

clean:
	rm -rf target build out $(VENV)

## --- documentation and installation ------------------------------------------
# `make reference`: docs/guide/case-file.md is generated from the doc comments of the case-file
# structs (the source of `asperity schema`); tests/case_file_reference.rs fails when the
# committed page differs.
reference: build
	$(BIN) schema --markdown > docs/guide/case-file.md
	@echo "wrote docs/guide/case-file.md"

# `make install PREFIX=~/.local` (default /usr/local; DESTDIR for packaging): the binary, the man
# pages (man asperity, man asperity-run, ...) and the bash, zsh and fish completions, each in the
# folder its shell reads by default under PREFIX.
PREFIX ?= /usr/local
INSTALL_ROOT = $(DESTDIR)$(PREFIX)
install: build
	install -D -m 755 $(BIN) $(INSTALL_ROOT)/bin/asperity
	$(INSTALL_ROOT)/bin/asperity man --out $(INSTALL_ROOT)/share/man/man1 >/dev/null
	install -d $(INSTALL_ROOT)/share/bash-completion/completions $(INSTALL_ROOT)/share/zsh/site-functions \
	  $(INSTALL_ROOT)/share/fish/vendor_completions.d
	$(INSTALL_ROOT)/bin/asperity completions bash > $(INSTALL_ROOT)/share/bash-completion/completions/asperity
	$(INSTALL_ROOT)/bin/asperity completions zsh > $(INSTALL_ROOT)/share/zsh/site-functions/_asperity
	$(INSTALL_ROOT)/bin/asperity completions fish > $(INSTALL_ROOT)/share/fish/vendor_completions.d/asperity.fish
	@echo "installed asperity into $(INSTALL_ROOT) (bin, share/man/man1, completions); plots of an installed binary: set ASPERITY_PIPELINES=$(CURDIR)/pipelines"

# `make install-test` (part of `make test`): install into a scratch prefix and use what it installed.
install-test: build
	@rm -rf build/test/install
	@$(MAKE) --no-print-directory install PREFIX=$(CURDIR)/build/test/install >/dev/null
	@p=build/test/install; $$p/bin/asperity --version >/dev/null && \
	  grep -q '^\.TH asperity-run 1' $$p/share/man/man1/asperity-run.1 && \
	  bash -c "source $$p/share/bash-completion/completions/asperity && complete -p asperity" >/dev/null && \
	  grep -q '^#compdef asperity' $$p/share/zsh/site-functions/_asperity && \
	  grep -q '^complete -c asperity' $$p/share/fish/vendor_completions.d/asperity.fish \
	  || { echo "install-test: the installed binary, man page or completions are missing or broken"; exit 1; }
	@echo "install-test: binary, man pages and completions installed and usable"

## --- examples gallery ------------------------------------------------------------
# examples/<NAME>/README.md says what each shows and the figures it makes. The examples that
# existed before the gallery keep their own targets (make shrink_fit, ...); these are aliases.
GALLERY := slideway shrink_fit tapered_joint fretting taper_torque fit sweep
example:
	@if [ -z "$(NAME)" ] || ! echo " $(GALLERY) " | grep -q " $(NAME) "; then \
	  echo "usage: make example NAME=<name>, one of: $(GALLERY) (examples/README.md)"; exit 2; fi
	@$(MAKE) --no-print-directory example-$(NAME)

SLIDEWAY_OUT ?= out/slideway
example-slideway: deps build
	$(PYTHON) pipelines/slideway/report.py --out $(SLIDEWAY_OUT) $(if $(QUICK),--quick) >/dev/null
	@echo "results: $(SLIDEWAY_OUT) (REPORT.md, force_displacement.png, stick_zone.png; run/results.pvd for ParaView)"
example-shrink_fit: shrink_fit
example-tapered_joint: tapered_joint
example-fretting: fretting
example-taper_torque: taper_torque
example-fit: fit-example

SWEEP_OUT ?= out/sweep/specimen
example-sweep: export ASPERITY_PIPELINES := $(CURDIR)/pipelines
example-sweep: venv build
	$(BIN) sweep plan examples/sweep/specimen.toml --out $(SWEEP_OUT)
	$(BIN) sweep run $(SWEEP_OUT)
	$(BIN) sweep collect $(SWEEP_OUT)
	@echo "results: $(SWEEP_OUT) (sweep.csv, force.png, iterations.png; runs/NNNN/ one folder per run)"

# `make examples-test` (part of `make test`): every gallery folder is listed in GALLERY and has
# its README; the slideway and taper_torque examples run in their quick forms with their checks. The others are
# checked by the tests above (tapered_joint --quick, shrink_fit, the fretting scripts,
# fit-example, sweep-test).
examples-test: deps build
	@for d in examples/*/; do n=$$(basename $$d); \
	  echo " $(GALLERY) " | grep -q " $$n " || { echo "examples/$$n is not in GALLERY"; exit 1; }; \
	  test -s $$d/README.md || { echo "examples/$$n has no README.md"; exit 1; }; done
	@for n in $(GALLERY); do test -d examples/$$n || { echo "GALLERY lists $$n, examples/$$n is missing"; exit 1; }; done
	@echo "example slideway (coarse)"
	@$(MAKE) --no-print-directory example-slideway QUICK=1 SLIDEWAY_OUT=build/test/slideway >/dev/null
	@test -s build/test/slideway/force_displacement.png && test -s build/test/slideway/stick_zone.png \
	  || { echo "example slideway: figures missing"; exit 1; }
	@echo "example taper_torque (coarse)"
	@$(MAKE) --no-print-directory taper_torque QUICK=1 TAPER_TORQUE_OUT=build/test/taper_torque >/dev/null

## --- torque (issue 25) ------------------------------------------------------------
# `make taper_torque`: the tapered joint seated by an axial load, twisted at its head until the
# whole cone slips (torque-twist curve, slip torque against the friction torque of the run's
# own pressure), then a reversed torque below the slip torque with fretting wear ->
# out/taper_torque (REPORT.md, torque_twist.png, cone.png, fretting.png; twist/ and fretting/
# one run folder each). The target fails when a check of REPORT.md fails; QUICK=1 runs a coarse
# mesh and fewer cycles (make examples-test).
.PHONY: taper_torque
TAPER_TORQUE_OUT ?= out/taper_torque
taper_torque: deps build
	$(PYTHON) pipelines/taper_torque/report.py --out $(TAPER_TORQUE_OUT) $(if $(QUICK),--quick) >/dev/null
	@echo "results: $(TAPER_TORQUE_OUT) (REPORT.md, torque_twist.png, cone.png, fretting.png; twist/ and fretting/ with results.pvd for ParaView)"

## --- cyclic plasticity (issue 27) ------------------------------------------------
# `make cyclic_press_fit`: the press fit under cyclic external pressure with isotropic and
# with kinematic hardening side by side -> out/cyclic_press_fit (REPORT.md, loops.png,
# local_loops.png, cycles.png, one run folder per hardening). Its quick form is
# tests/cyclic_press_fit.rs.
.PHONY: cyclic_press_fit
CYCLIC_OUT ?= out/cyclic_press_fit
cyclic_press_fit: deps build
	@for h in isotropic kinematic; do \
	  $(BIN) run pipelines/cyclic_press_fit/$$h.toml --out $(CYCLIC_OUT)/$$h --force || exit 1; \
	done
	$(PYTHON) pipelines/cyclic_press_fit/report.py $(CYCLIC_OUT)
	@echo "results: $(CYCLIC_OUT) (REPORT.md, loops.png, local_loops.png, cycles.png, results.pvd per run for ParaView)"

## --- temperature (issue 26) -----------------------------------------------------
# Each example runs its case (pipelines/<name>/case.toml) in variants, checks it against closed
# forms and writes REPORT.md with the figures; the target fails when a check fails.
# `make thermal-test` runs their quick forms (coarse meshes) for `make test`.
.PHONY: joint_thermal shrink_fit_thermal thermal-test

#   make shrink_fit_thermal      hub heated to clear the shaft, then cooled onto it (Lamé) -> out/shrink_fit_thermal
#   make joint_thermal           slideway joint with a heat source: pressure-dependent joint conductance -> out/joint_thermal
shrink_fit_thermal joint_thermal: deps build
	$(PYTHON) pipelines/$@.py --out out/$@
	@echo "results: out/$@ (REPORT.md, figures, one folder per run with results.pvd for ParaView)"

thermal-test: deps build
	@mkdir -p build/test
	@for e in shrink_fit_thermal joint_thermal; do \
	  echo "example $$e (coarse)"; \
	  $(PYTHON) pipelines/$$e.py --quick --out build/test/$$e >build/test/$$e.txt 2>&1 || { cat build/test/$$e.txt; exit 1; }; \
	done
