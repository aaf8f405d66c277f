# `make demo` and `make test` work on a fresh machine: each creates .venv if missing,
# installs torch 2.13.0 (CPU) before anything that depends on torch, then the project.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# the page's three.js and msgpack (`npm ci`); defined before the first rule that names it (make expands prerequisites
# as it reads them)
NODE_STAMP := node_modules/.installed

.PHONY: demo test test-fast docs bench venv clean web-deps browser wheel benchmarl-venv

venv: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet torch==2.13.0
	$(PY) -m pip install --quiet -e '.[train,test,web,cluster,rlgym,docs]'
	$(PY) -m pip install --quiet --no-deps rlgym-rocket-league==2.0.1  # its numpy<2 pin is stale (docs/guides/rlgym.md)
	touch $(STAMP)

# The physics kernels compiled once (numba's cache), then the shipped 2v2 team against two scripted rotators on a
# 3-minute clock (overtime capped at 30 s), with the score live; its replay opens in `rocketdrl-ma web`.
demo: $(STAMP) $(NODE_STAMP)
	$(PY) -m rocketdrl_ma.cli warmup
	$(PY) -m rocketdrl_ma.cli play matches/2v2.yaml --blue checkpoint:policies/checkpoints/selfplay_2v2_from_1v1.pt \
		--orange rotator --clock 180 --set overtime_limit_s=30 --replay runs/demo/2v2.npz

# The page of `rocketdrl-ma web`: three.js and msgpack from the npm registry, exactly as package-lock.json says.
web-deps: $(NODE_STAMP)

$(NODE_STAMP): package.json package-lock.json
	command -v npm >/dev/null || (apt-get update && apt-get install -y --no-install-recommends nodejs npm)
	npm ci --no-audit --no-fund
	touch $(NODE_STAMP)

# The wheel (dist/): the package with the shipped configs, checkpoints and the page's three.js (setup.py).
wheel: $(STAMP) $(NODE_STAMP)
	$(PY) -m pip wheel --no-deps -w dist .

# BenchMARL (docs/guides/benchmarl.md) in a venv of its own: the [benchmarl] extra's torchrl <0.12 and the [train]
# extra's torchrl 0.14 cannot share one. One pip command with torch named in it, so torchvision (a BenchMARL
# dependency) cannot pull a CUDA torch.
BENCHMARL_VENV := .venv-benchmarl
BENCHMARL_STAMP := $(BENCHMARL_VENV)/.installed
benchmarl-venv: $(BENCHMARL_STAMP)

$(BENCHMARL_STAMP): pyproject.toml
	test -x $(BENCHMARL_VENV)/bin/python || $(PYTHON) -m venv $(BENCHMARL_VENV)
	$(BENCHMARL_VENV)/bin/python -m pip install --quiet --upgrade pip
	$(BENCHMARL_VENV)/bin/python -m pip install --quiet torch==2.13.0 -e '.[benchmarl]'
	touch $(BENCHMARL_STAMP)

# The browser of tests/web: Debian's chromium (Playwright drives it; no `playwright install`).
browser:
	command -v chromium >/dev/null || (apt-get update && apt-get install -y --no-install-recommends chromium)

# The suite runs as two pytest sessions side by side. The wall-clock tests (`wall_clock`, tests/conftest.py: servers
# with lockstep deadlines, bots, the browser) run in one process at normal priority: beside another test at the same
# priority they missed deadlines. Everything else runs at the lowest priority (nice 19) on two pytest-xdist workers
# (XDIST; loadgroup keeps the tests of one xdist_group, a module with costly module fixtures or the Ray tests, on one
# worker), so it takes only the CPU the wall-clock tests leave. Its output is kept in runs/test-compute.log and
# printed when both are done; the target fails if either session did. In one process the suite took 20:38 on 2 cores.
XDIST ?= -n 2 --dist loadgroup
PYTEST := $(PY) -m pytest -q -p no:cacheprovider
COMPUTE_LOG := runs/test-compute.log

# $(call suite,MARKS): the two sessions over the tests that MARKS (a -m expression ending in "and", or empty) selects
define suite
	@mkdir -p runs
	nice -n 19 $(PYTEST) $(XDIST) -m "$(1) not wall_clock" tests > $(COMPUTE_LOG) 2>&1 & compute=$$!; \
	$(PYTEST) -m "$(1) wall_clock" tests; clock=$$?; \
	wait $$compute; rest=$$?; cat $(COMPUTE_LOG); \
	test $$rest -eq 0 && test $$clock -eq 0
endef

# The documentation site, built strict (a broken link, snippet or API reference fails it) into runs/site.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --site-dir runs/site

# The whole suite, slow-marked tests included: correctness is never skipped. The docs build is part of it.
test: $(STAMP) $(NODE_STAMP) browser $(BENCHMARL_STAMP) docs
	$(call suite,)

# Everything but the tests marked slow, for quick local iteration.
test-fast: $(STAMP) $(NODE_STAMP) browser
	$(call suite,not slow and)

bench: $(STAMP)
	$(PY) benchmarks/physics_speed.py
	$(PY) benchmarks/throughput.py
	$(PY) benchmarks/fidelity.py

clean:
	rm -rf $(VENV) $(BENCHMARL_VENV) build dist *.egg-info node_modules
