# `make run`: set up .venv and run the main job on bundled data; `make test`: set up and run the tests.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	$(PY) -m pip install --quiet --no-deps "trackeval>=1.3.0"
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/vistrack track data/pets09-s2l1/pets09-s2l1.mp4 --gt data/pets09-s2l1/gt.txt \
		--out-dir out/pets09-s2l1 --force
	$(VENV)/bin/vistrack demo kalman --out out/

test: $(STAMP)
	$(PY) -m pytest -q

$(VENV)/.bench-installed: $(STAMP)
	$(PY) -m pip install --quiet -e ".[test,bench]"
	touch $@

bench: $(VENV)/.bench-installed
	$(PY) bench/bench_kalman.py --write docs/benchmarks.md
	$(PY) bench/bench_particle.py --write docs/benchmarks.md
	$(PY) bench/bench_tracking.py --write docs/benchmarks.md
	$(PY) bench/bench_pixels.py --write docs/benchmarks.md
	$(PY) bench/bench_microscopy.py --write docs/benchmarks.md
	$(PY) bench/bench_single.py --write docs/benchmarks.md
	$(PY) bench/bench_snake.py --write docs/benchmarks.md
	$(PY) bench/accuracy_mot.py --write docs/mot.md
	$(PY) bench/accuracy_mot.py --offline --write docs/mot.md

clean:
	rm -rf $(VENV) out build src/*.egg-info
