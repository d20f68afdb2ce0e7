# The README's two commands.  `make lab` opens the notebooks; `make test` runs every test and
# every notebook (DDP_PROFILE=ci).  Both create .venv on first use and skip the install when
# environment.txt and pyproject.toml have not changed since the last one.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.ddp-lite-installed

.PHONY: lab test install clean-venv

install: $(STAMP)

$(PY):
	$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 10), "ddp-lite needs Python >= 3.10, found " + sys.version.split()[0]'
	$(PYTHON) -m venv $(VENV)

# torch goes first and pinned: anything that pulls a newer torch downloads a multi-GB CUDA build.
$(STAMP): $(PY) environment.txt pyproject.toml
	$(PY) -m pip install --disable-pip-version-check -q "$$(grep -E '^torch==' environment.txt)"
	$(PY) -m pip install --disable-pip-version-check -q -r environment.txt
	$(PY) -m pip install --disable-pip-version-check -q --no-deps -e .
	touch $(STAMP)

lab: $(STAMP)
	$(VENV)/bin/jupyter lab notebooks/

test: $(STAMP)
	DDP_PROFILE=ci MPLBACKEND=Agg $(PY) -m pytest tests --nbval-lax --nbval-current-env notebooks -p no:cacheprovider

clean-venv:
	rm -rf $(VENV)
