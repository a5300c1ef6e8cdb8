# Two commands do all set-up on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= results/demo
# compiled and traced programs are reused across processes: `make demo` fills the user's cache
# (~/.cache/bearingsim/jax, as every later `bearingsim` command uses it); `make test` uses its own
# .jax_cache, shared by the test workers, notebooks and CLI subprocesses of the run
test: export JAX_COMPILATION_CACHE_DIR ?= $(CURDIR)/.jax_cache
# every program, the small ones too: the 9 notebook kernels, the 2 workers and the CLI subprocesses
# share ~45 sub-0.1 s programs each (notebook 01, warm cache: 8.3 s user with 0, 9.0 s with 0.5)
export JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS ?= 0
# one pytest worker per core (2 on CI); each file stays on one worker, so its compiled programs
# are compiled once; files go out longest first (tests/conftest.py HEAVY_FIRST, xdist's
# reorder by test count off) so both workers finish together
JOBS ?= 2
# the suite is compile-bound (hundreds of programs, each run for milliseconds): LLVM at -O0
# compiles them ~40 % faster for the same results (tests/test_verdicts.py + test_chunk_program.py,
# cold cache, 2-core VM: 126 s -> 75 s of CPU); `make demo`, the benchmarks and users keep XLA's
# optimised default.  XLA_FLAGS= make test runs the suite at the default level.
test: export XLA_FLAGS ?= --xla_backend_optimization_level=0
# the xdist workers already fill the cores: a data set's chunks run one at a time in a test
# (tests/test_dataset_engine.py runs them side by side on purpose and compares the bytes)
test: export BEARINGSIM_THREADS ?= 1

# pip compiles the bytecode of every installed file one at a time; compileall does the same files
# on every core (a fresh venv with a warm pip cache, 2-core VM, 2026-11-28: 41 s -> 31 s, the same
# 13 339 .pyc files; make demo 56 -> 48 s; make test inside its run-to-run spread, docs/scale.md).
# Compiling only what a run imports (23 s) left the rest to the test workers' first imports.
SITE = $(PY) -c "import sysconfig; print(*sorted({sysconfig.get_path(k) for k in ('purelib', 'platlib')}))"

.PHONY: demo test venv clean bench

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --no-compile -e ".[test]"
	$(PY) -m compileall -q -j 0 bearingsim $$($(SITE)) > /dev/null || true   # as pip: a file that does not compile is not an install error
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/bearingsim demo --out $(OUT)

test: $(STAMP)
	$(PY) -m pytest -q -p no:cacheprovider -n $(JOBS) --dist loadfile --no-loadscope-reorder tests $(wildcard notebooks/*.ipynb) --nbmake --durations=20

bench: $(STAMP)
	$(PY) benchmarks/bench_compile.py
	$(PY) benchmarks/bench_static.py
	$(PY) benchmarks/bench_sweep.py
	$(PY) benchmarks/bench_validity.py
	$(PY) benchmarks/bench_dynamics.py
	$(PY) benchmarks/bench_scale.py
	$(PY) benchmarks/bench_sets.py

clean:
	rm -rf $(VENV) results build *.egg-info
