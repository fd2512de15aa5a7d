# HC Smooth: set-up, tests, demo and build. Every target installs what it needs (see scripts/setup_envs.sh).
ENVS := bpy45 bpy52
PY45 := .envs/bpy45/bin/python
# Extra pytest arguments, e.g. `make test PYTEST_ARGS="-k hc -x"`; test paths among them replace `tests`
# (`make test PYTEST_ARGS="-q tests/blender/test_examples.py"` runs that file on both Blenders).
PYTEST_ARGS ?=
TEST_PATHS := $(if $(filter tests%,$(PYTEST_ARGS)),,tests)
# A hung interpreter must fail the run, not stall CI: each environment's suite gets this many seconds.
TEST_TIMEOUT ?= 1200

.PHONY: envs env-bpy45 env-bpy52 env-lint env-bench test test-core test-quick lint format demo build dist clean

# Both test environments and the benchmarks' (tests/bench runs every benchmark's smoke run in it);
# `make env-bpy45` / `make env-bpy52` / `make env-bench` makes one alone.
envs: env-bpy45 env-bpy52 env-bench

env-bpy45 env-bpy52 env-lint env-bench:
	bash scripts/setup_envs.sh $(@:env-%=%)

# Style (pyproject.toml): ruff's lint rules and its formatting, checked; `make format` applies both.
lint: env-lint
	.envs/lint/bin/ruff check --no-cache .
	.envs/lint/bin/ruff format --no-cache --check .

format: env-lint
	.envs/lint/bin/ruff check --no-cache --fix .
	.envs/lint/bin/ruff format --no-cache .

# The whole suite (core + headless Blender) on Blender 4.5 LTS and Blender 5.2 LTS; fails if either fails.
test: envs
	@status=0; for env in $(ENVS); do \
	  echo "=== tests on $$env ==="; \
	  timeout $(TEST_TIMEOUT) .envs/$$env/bin/python -m pytest -p no:cacheprovider $(PYTEST_ARGS) $(TEST_PATHS) || status=1; \
	done; exit $$status

# Core only, with whatever python3 has NumPy, SciPy, pytest and hypothesis.
test-core:
	python3 -m pytest -q tests/core

# Core without the tests marked slow (tests/pytest.ini), on Blender 4.5's Python: a check while editing.
test-quick: env-bpy45
	$(PY45) -m pytest -q -p no:cacheprovider -m "not slow" tests/core

# The main job: a headless demo on a built-in default (noisy subdivided Suzanne), on Blender 4.5 only.
demo: env-bpy45
	$(PY45) demo/demo.py

# The extension zip, built by Blender's own extension tool.
build: env-bpy45
	$(PY45) scripts/build_extension.py

# One zip per platform with SciPy wheels for Blender 4.2-5.0 (cp311) and 5.1+ (cp313), validated, in dist/.
# Downloads the wheels from PyPI once into build/wheels.
dist: env-bpy45
	$(PY45) scripts/dist.py

clean:
	rm -rf build dist demo_output
