# `make run`: set up .venv and run the main job on bundled data; `make test`: set up and run the tests;
# `make docs`: build the documentation site (docs/_build/html), warnings as errors;
# `make lint`: ruff and mypy, as configured in pyproject.toml.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
# vistrack installed editable, built in .venv itself rather than in an isolated environment that
# would install numba, numpy and the rest a second time; its kernels are compiled by `make
# kernels`, with .venv's numba
INSTALL_E := VISTRACK_PREBUILT=0 $(PY) -m pip install --quiet --no-build-isolation -e

.PHONY: run test docs lint bench bench-peers clean kernels

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml setup.py | $(PY)
	$(PY) -m pip install --quiet --upgrade pip "setuptools>=77" wheel
	$(INSTALL_E) ".[test]"
	$(PY) -m pip install --quiet --no-deps "trackeval>=1.3.0"
	touch $(STAMP)

# the kernels compiled ahead of time (as setup.py does on pip install): rebuilt when a source changed since; if that
# fails (no C compiler), vistrack compiles them on first use instead. numba's compilations of
# them are kept in build/numba-cache, where the tests' processes load them from
kernels: $(STAMP)
	-$(PY) -m vistrack._prebuilt_build build --inplace --if-stale --numba-cache build/numba-cache

run: kernels
	$(VENV)/bin/vistrack demo track --out out --force
	$(VENV)/bin/vistrack demo kalman --out out/

# the whole suite, slow-marked checks included, on every core (pytest-xdist; a worker that
# runs out of tests takes some of another's, so the long ones do not leave a core idle at the end)
test: kernels
	$(PY) -m pytest -q -n auto --dist worksteal

$(VENV)/.lint-installed: $(STAMP)
	$(INSTALL_E) ".[lint]"
	touch $@

lint: $(VENV)/.lint-installed
	$(VENV)/bin/ruff check
	$(VENV)/bin/mypy

$(VENV)/.docs-installed: $(STAMP)
	$(INSTALL_E) ".[docs]"
	touch $@

# the API pages are generated from each module's __all__: start them afresh, so that a removed
# name leaves no stale page behind
docs: $(VENV)/.docs-installed
	rm -rf docs/api/generated
	$(VENV)/bin/sphinx-build -W --keep-going -b html docs docs/_build/html

$(VENV)/.bench-installed: $(STAMP)
	$(INSTALL_E) ".[test,bench]"
	# supervision (for trackers) pulls opencv-python, whose cv2 lacks the contrib modules
	# (HOG) and overwrites ours: put opencv-contrib-python-headless back over it
	$(PY) -m pip install --quiet --force-reinstall --no-deps \
		"$$($(PY) -m pip freeze | grep -i '^opencv-contrib-python-headless==')"
	touch $@

bench: $(VENV)/.bench-installed
	$(PY) bench/bench_kalman.py --write docs/benchmarks.md
	$(PY) bench/bench_em.py --write docs/benchmarks.md
	$(PY) bench/bench_particle.py --write docs/benchmarks.md
	$(PY) bench/bench_tracking.py --write docs/benchmarks.md
	$(PY) bench/bench_pixels.py --write docs/benchmarks.md
	$(PY) bench/bench_microscopy.py --write docs/benchmarks.md
	$(PY) bench/bench_single.py --write docs/benchmarks.md
	$(PY) bench/bench_snake.py --write docs/benchmarks.md
	$(PY) bench/accuracy_mot.py --write docs/mot.md
	$(PY) bench/accuracy_mot.py --every 3 --write docs/mot.md
	$(PY) bench/accuracy_mot.py --every 6 --write docs/mot.md

# boxmot for bench/accuracy_mot.py, in an environment of its own: it pins filterpy<2 and
# opencv-python<5, and pulls torch (several GB)
.venv-boxmot/bin/python:
	$(PYTHON) -m venv .venv-boxmot
	.venv-boxmot/bin/python -m pip install --quiet "torch==2.14.1" "torchvision==0.29.1" "boxmot==25.0.0"

# dynamax for bench/bench_em.py, in an environment of its own: it needs jax
.venv-dynamax/bin/python:
	$(PYTHON) -m venv .venv-dynamax
	.venv-dynamax/bin/python -m pip install --quiet "jax==0.10.2" "jaxlib==0.10.2" "dynamax==1.0.3"

bench-peers: .venv-boxmot/bin/python .venv-dynamax/bin/python

clean:
	rm -rf $(VENV) out build src/*.egg-info docs/_build docs/api/generated src/vistrack/_kernels*.so \
		src/vistrack/_kernels.json
