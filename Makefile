# The README's two commands.  `make lab` opens the notebooks; `make test` runs every test and
# every notebook (DDP_PROFILE=ci).  Both create .venv on first use and skip the install when
# environment.txt and pyproject.toml have not changed since the last one.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.ddp-lite-installed

.PHONY: lab lab-command test install clean-venv student solutions grade classroom-check

# `make lab` serves $(LAB_DIR) on $(IP):$(PORT) and prints the URL with its token: notebooks/ (the
# instructor's, solutions in) or, for a student, `make lab LAB_DIR=build/student` (`make student`).  --allow-root
# only for root (Jupyter refuses root without it); --no-browser on Linux & co. without a display
# (macOS always has one).  tests/notebooks/test_lab.py runs exactly $(LAB_CMD), via `make -s lab-command`.
PORT ?= 8888
IP   ?= 127.0.0.1
LAB_DIR ?= notebooks/
LAB_ARGS := $(LAB_DIR) --ip=$(IP) --port=$(PORT)
ifeq ($(shell id -u),0)
LAB_ARGS += --allow-root
endif
ifneq ($(shell uname -s),Darwin)
ifeq ($(strip $(DISPLAY)$(WAYLAND_DISPLAY)),)
LAB_ARGS += --no-browser
endif
endif
# The notebooks' fits and scenes are kept in $(DDP_CACHE) (ddp_lite.method.fit_cache, ddp_lite.world.scene_cache): a
# notebook run again, after a kernel restart or an edit further down, reads them back in seconds instead of minutes.
# `DDP_CACHE= make lab` keeps nothing; `rm -r .cache/fits` frees the space (a few MB per fit).
DDP_CACHE ?= $(CURDIR)/.cache/fits
LAB_CMD := env DDP_CACHE=$(DDP_CACHE) $(VENV)/bin/jupyter lab $(LAB_ARGS)

install: $(STAMP)

# The venv's pip is the one its Python bundles (ensurepip's wheel), installed by running it from that wheel without
# byte-compiling it (`python -m venv` compiles pip and setuptools: 6-8 s of the install); where that fails, ensurepip.
$(PY):
	$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 10), "ddp-lite needs Python >= 3.10, found " + sys.version.split()[0]'
	$(PYTHON) -m venv --without-pip $(VENV)
	wheel=$$($(PY) -c 'import ensurepip, glob, os; print(glob.glob(os.path.join(os.path.dirname(ensurepip.__file__), "_bundled", "pip-*.whl"))[0])') \
	  && $(PY) "$$wheel/pip" install -q --no-compile --no-index --disable-pip-version-check "$$wheel" \
	  || $(PY) -m ensurepip --default-pip

# torch is pinned: anything that pulls a newer torch downloads a multi-GB CUDA build.
# pip does not byte-compile (--no-compile): of the 2.6 GB stack the tests and notebooks import about a fifth
# of the files, and Python compiles each on its first import and caches it (below), so compiling all of
# site-packages at install time spent about 4x the CPU on files nothing imports.
# The stack goes in through uv (Astral's installer, pinned below), which fetches and unpacks the ~170 pinned
# packages in parallel: about 5x faster than pip here (35 s against 180 s on 2 cores).  uv does not read pip's
# configuration, which on some machines points at a CPU build of torch on disk (find-links): so pip is asked
# where it would take torch from (a dry run, ~3 s, while pip installs uv beside it) and, where that is a file,
# uv installs that file with the rest and the kit, in one call (4 s against pip's 15 s for torch); otherwise pip
# installs torch first, as it would alone.  Without uv (no registry), pip does it all.
PIP := $(PY) -m pip install --disable-pip-version-check -q --no-compile
UV_PIN := uv==0.13.8
UV := $(VENV)/bin/uv pip install -q --python $(PY)
TORCH_PIN = $$(grep -E '^torch==' environment.txt)
TORCH_REPORT := $(VENV)/.torch-report.json
TORCH_FILE = $$($(PY) -c \
	'import json; url = json.load(open("$(TORCH_REPORT)"))["install"][0]["download_info"]["url"]; print(url if url.startswith("file:") else "")' \
	2>/dev/null)

$(STAMP): $(PY) environment.txt pyproject.toml
	rm -f $(TORCH_REPORT); $(PIP) --dry-run --no-deps --report $(TORCH_REPORT) "$(TORCH_PIN)" >/dev/null 2>&1 & \
	if $(PIP) "$(UV_PIN)"; then wait; \
	  torch_file=$(TORCH_FILE); \
	  if [ -n "$$torch_file" ]; then $(UV) -r environment.txt "torch @ $$torch_file" -e .; \
	  else $(PIP) "$(TORCH_PIN)" && $(UV) -r environment.txt -e .; fi; \
	else wait; $(PIP) "$(TORCH_PIN)" && $(PIP) -r environment.txt && $(PIP) --no-deps -e .; fi
	rm -f $(TORCH_REPORT)
	touch $(STAMP)

# Python caches the bytecode of what it imports (in .venv and the checkout's __pycache__) unless
# PYTHONDONTWRITEBYTECODE is set, as it is on some machines: then every test process and notebook kernel
# would compile torch again. The commands below let it cache.
unexport PYTHONDONTWRITEBYTECODE

lab: $(STAMP)
	$(LAB_CMD)

lab-command:
	@echo '$(LAB_CMD)'

# The tests and notebooks run in $(TEST_WORKERS) processes (pytest-xdist; each file stays in one, so a
# notebook's cells run in order in one kernel, but the student copies are spread one per notebook;
# tests/conftest.py puts the notebooks first, slowest first, and the student copies right after them,
# which read the notebooks' fits from the session's fit cache),
# each with one torch thread: on 2 cores, two 1-thread processes finish sooner than
# one 2-thread process, because most of a test is Python, not arithmetic. TEST_WORKERS=0 runs
# everything in one process (torch then takes 2 threads). The notebook kernels the workers start are forked from
# one that has imported the notebooks' stack (tests/kernel_forkserver.py); DDP_TEST_FRESH_KERNELS=1 starts each fresh.
TEST_WORKERS ?= 2

TEST_CMD := DDP_PROFILE=ci MPLBACKEND=Agg $(if $(filter 0,$(TEST_WORKERS)),,OMP_NUM_THREADS=1) $(PY) -m pytest tests --nbval-lax --nbval-current-env notebooks -p no:cacheprovider -n $(TEST_WORKERS) --dist loadfile --no-loadscope-reorder

# `make test` ends with its time in all, counted from make's start, the install (when it ran) included.
ifneq ($(filter test,$(MAKECMDGOALS)),)
TEST_START := $(shell date +%s)
endif

test: $(STAMP)
	@installed=$$(date +%s); echo '$(TEST_CMD)'; $(TEST_CMD); status=$$?; end=$$(date +%s); \
	span() { printf '%d min %02d s' $$(($$1 / 60)) $$(($$1 % 60)); }; \
	echo "make test: $$(span $$((end - $(TEST_START)))) in all (install $$(span $$((installed - $(TEST_START)))), tests $$(span $$((end - installed)))), exit $$status"; \
	exit $$status

# The classroom kit (README, "For instructors"). notebooks/ is the instructor version; `student`
# strips solutions and outputs, `solutions` executes every notebook at $(SOLUTIONS_PROFILE) (class:
# minutes per notebook), `grade` runs $(SUBMISSIONS)/<student>/*.ipynb at ci and writes $(GRADES).
# They run $(VENV)/bin/ddp-lite: with the default VENV=.venv they install it first (as `make lab`),
# with VENV=DIR (an environment of your own that has ddp-lite) they install nothing.
SOLUTIONS_PROFILE ?= class
SUBMISSIONS ?= submissions
GRADES ?= grades.csv
GRADE_ARGS ?=
DDP_LITE := $(VENV)/bin/ddp-lite
CLASSROOM_NEEDS := $(if $(filter .venv,$(VENV)),$(STAMP),)

classroom-check:
	@test -x $(DDP_LITE) || { echo "$(DDP_LITE) not found: VENV=$(VENV) must be an environment with ddp-lite installed (pip install -e .)"; exit 2; }

student: $(CLASSROOM_NEEDS) classroom-check
	$(DDP_LITE) student --source notebooks --out build/student

solutions: $(CLASSROOM_NEEDS) classroom-check
	$(DDP_LITE) solutions --source notebooks --out build/solutions --profile $(SOLUTIONS_PROFILE)

grade: $(CLASSROOM_NEEDS) classroom-check
	$(DDP_LITE) grade $(SUBMISSIONS) --source notebooks --csv $(GRADES) $(GRADE_ARGS)

clean-venv:
	rm -rf $(VENV)
