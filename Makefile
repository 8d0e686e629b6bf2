# ancf-petsc — every target bootstraps the environment first (scripts/setup.sh, idempotent).
SHELL := /bin/bash
VENV  := .venv
PY    := $(VENV)/bin/python
export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
export OMPI_MCA_rmaps_base_oversubscribe := 1
export OPENBLAS_NUM_THREADS := 1
export OMP_NUM_THREADS := 1
MPIRUN := mpirun --oversubscribe
DEMO_CONFIG ?= configs/achilles_type3_psi45.yaml
DEMO_OUT    ?= results/achilles_type3_psi45

.PHONY: setup demo report test test-fast bench bench-iteration bench-scaling bench-growth verify verify-solid verify-solid-references verify-solid-contact verify-solid-contact-plane verify-solid-friction verify-solid-friction-refined verify-friction-orders studies clean

setup:
	@bash scripts/setup.sh

demo: setup
	$(MPIRUN) -n 2 $(VENV)/bin/ancf-solve $(DEMO_CONFIG) --output-dir $(DEMO_OUT)
	$(VENV)/bin/ancf-report --existing $(DEMO_OUT) --out $(DEMO_OUT)/report
	@echo "[demo] table: $(DEMO_OUT)/report/report.md; plots: $(DEMO_OUT)/report/*.png;"
	@echo "[demo] ParaView: $(DEMO_OUT)/surface.pvd; data: $(DEMO_OUT)/results.h5, summary.json"

report: setup
	$(VENV)/bin/ancf-report --jobs 2

# the tests without the mpi mark on TEST_JOBS pytest-xdist workers, then the MPI tests one at a
# time (each starts mpirun with 2 or 3 ranks; beside another worker they would oversubscribe the
# cores).  tests/conftest.py refuses mpirun in a test without the mark.
TEST_JOBS ?= $(shell nproc 2>/dev/null || echo 2)

test: setup
	$(PY) -m pytest -q -rs -n $(TEST_JOBS) -m "not mpi" tests
	$(PY) -m pytest -q -rs -m mpi tests

test-fast: setup
	$(PY) -m pytest -q -rs -n $(TEST_JOBS) -m "not slow and not mpi" tests

bench: setup
	$(PY) scripts/bench_kernel.py

# a Newton iteration of the paper's tendon, start-up, the column and the kernel (docs/parallel.md);
# beside older checkouts: scripts/bench_iteration.py --baseline NAME=DIR ...
bench-iteration: setup
	$(PY) scripts/bench_iteration.py

bench-scaling: setup
	$(PY) scripts/bench_scaling.py

# how cost grows with the scene (7..91 fascicles, both linear solvers; about 20 min), then the
# MPI traffic at 2-4 ranks and the 64-rank projection from those measurements (docs/parallel.md)
bench-growth: setup
	$(PY) scripts/bench_growth.py
	$(PY) scripts/bench_scaling.py --quick --repeat 3
	$(PY) scripts/bench_scaling.py --messages
	$(PY) scripts/project_scaling.py

studies: setup
	$(VENV)/bin/ancf-study configs/studies/bending_pareto.yaml
	$(VENV)/bin/ancf-study configs/studies/bending_stability.yaml
	$(VENV)/bin/ancf-study configs/studies/achilles_pareto.yaml
	$(VENV)/bin/ancf-study configs/studies/achilles_stability.yaml
	$(PY) scripts/accuracy_demo.py

verify: setup
	$(PY) scripts/verification_report.py

# every 3D-solid reference re-solved on its coarsest mesh against its CSV, the contact solids'
# checks, then one table: each reference, its mesh convergence, the beams' error against it
# (a few minutes; VERIFY_SOLID_FLAGS=--quick: the table from the CSVs alone)
verify-solid: setup
	$(PY) scripts/verify_solid_summary.py $(VERIFY_SOLID_FLAGS)

# the bar, fibre and soft-matrix references made again on all their meshes (about 1 h)
verify-solid-references: setup
	$(PY) scripts/verify_solid.py
	$(PY) scripts/verify_solid_fibres.py
	$(PY) scripts/verify_solid_soft_matrix.py

verify-solid-contact: setup
	$(PY) scripts/verify_solid_contact.py
	$(PY) scripts/verify_solid_contact.py --merge --no-selftest --no-free --no-checks --laws unilateral \
		--psi 45 --h 2e-3,1.4e-3 --loads 10,20,40 --max-increment 10

# the same tendon on plane roots (u_x = 0, free in the plane; beams fix: plane), both laws at psi = 45 deg,
# 10-40 N, h = 2.0 and 1.4 mm, then with a pure penalty eps = k mu/h on 2.0 mm (docs/solid_contact.md,
# "The unilateral 10 N question on plane roots"; about 35 min on one shared core), then the CSV into docs/
verify-solid-contact-plane: setup
	$(PY) scripts/verify_solid_contact.py --root plane --no-selftest --no-free --no-checks --laws unilateral,sliding \
		--psi 45 --h 2e-3,1.4e-3 --loads 10,20,40 --max-increment 10 --out results/solid_contact_plane
	for k in 10 1 0.1 0.01; do $(PY) scripts/verify_solid_contact.py --root plane --merge --no-selftest --no-free \
		--no-checks --laws sliding,unilateral --psi 45 --h 2e-3 --loads 10,20,40 --max-increment 10 --penalty $$k \
		--out results/solid_contact_plane || exit 1; done
	cp results/solid_contact_plane/solid_contact.csv docs/solid_contact_plane.csv

# the three subtendons as 3D solids with Coulomb friction (mu = 0.3) against the beams with
# contact.tangential coulomb (docs/interface.md, "Against a 3D solid with friction"; a few hours),
# then the diagnostic without friction within 10 mm of the clamped roots (both models)
verify-solid-friction: setup
	$(PY) scripts/verify_solid_friction.py --profiles 10,100
	$(PY) scripts/verify_solid_friction.py --merge --no-selftest --free-zone 0.01 --ancf-augmentations default
	$(MAKE) verify-solid-friction-refined

# the friction reference refined at the soleus-medial interface (issue 41; docs/interface.md, "The friction
# reference, locally refined at the soleus-medial interface"): bulk h = 2 mm, 1.0 and 0.7 mm at mg_sol over
# Table 1's 13 levels, 0.5 mm over the levels to 100 N, 0.4 mm at 10 N; merged into docs/solid_friction.csv
# (10 + 32 + 33 + 101 min on one shared core, one process; peak resident memory 1.7 / 3.6 / 7.4 / 11.4 GB)
FRICTION_REFINED := --merge --psi 45 --no-selftest --no-checks --no-ancf --profiles=
verify-solid-friction-refined: setup
	$(PY) scripts/verify_solid_friction.py $(FRICTION_REFINED) --h 2e-3,2e-3 --h-interface 1e-3,7e-4
	$(PY) scripts/verify_solid_friction.py $(FRICTION_REFINED) --h 2e-3 --h-interface 5e-4 \
		--loads 10,20,30,40,45,60,80,90,100
	$(PY) scripts/verify_solid_friction.py $(FRICTION_REFINED) --h 2e-3 --h-interface 4e-4 --loads 10

# the section orders against the friction solid (issue 42; docs/interface.md, "Orders 3 and 4 against the
# friction solid"): the beams only (the solid rows are verify-solid-friction's), elements 33103 and 33153 with
# the pressure of degree 1, 2, 3 across at 4/8/16 elements and 3363 with degree 3 at 4/8 (3363's degrees 1
# and 2 are the plain ANCF rows), merged into docs/solid_friction.csv; the pressure across at 100 N (8 el.);
# the inf-sup study (docs/solid_friction_infsup.csv); the page's generated section again
FRICTION_ORDERS := --psi 45 --no-solid --merge --no-selftest --no-checks --ancf-augmentations default --profiles=
verify-friction-orders: setup
	for e in 33103 33153; do $(PY) scripts/verify_solid_friction.py $(FRICTION_ORDERS) --element $$e \
		--ancf-spaces "default;quadratic across;cubic across" || exit 1; done
	$(PY) scripts/verify_solid_friction.py $(FRICTION_ORDERS) --element 3363 --elements 4,8 --ancf-spaces "cubic across"
	$(PY) scripts/solid_friction_across.py --no-solid --mu 0.3 --elements 8 --element 33103 \
		--spaces "quadratic across;default"
	$(PY) scripts/solid_friction_across.py --no-solid --mu 0.3 --elements 8 --element 33153 \
		--spaces "cubic across;quadratic across"
	$(PY) scripts/solid_friction_across.py --no-solid --mu 0 --elements 8 --element 33153 --spaces "cubic across"
	$(PY) scripts/solid_friction_across.py --no-solid --mu 0 --elements 8 --element 33103 --spaces "quadratic across"
	$(PY) scripts/friction_orders.py --infsup
	$(PY) scripts/verify_solid_friction.py --replot

clean:
	rm -rf results .pytest_cache
