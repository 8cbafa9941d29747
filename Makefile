# sonotrack: everything a fresh clone needs, from a machine with Python 3.11, make and a C
# compiler.
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
FMU_DIR := fmus
SCENARIO ?= scenarios/s_curve.toml

# sonotrack's FMI 2.0 binary (linux64), compiled against the FMI headers fmpy ships from every
# C source and header in orchestrator/builder/fmi_binary/ (a change to any of them rebuilds it). The
# library carries the sha256 of those sources; `sonotrack build` refuses one built from others.
FMI_BINARY := orchestrator/builder/fmi_binary/linux64/sonotrack_fmi2.so
# The process-wide lock is a library of its own that every copy of the main library needs by name
# (process_lock.c says why); the main library finds it beside itself ($ORIGIN).
FMI_LOCK := orchestrator/builder/fmi_binary/linux64/libsonotrack_fmi2_lock.so.1
FMI_LOCK_SOURCE := orchestrator/builder/fmi_binary/process_lock.c
FMI_SOURCES := $(filter-out $(FMI_LOCK_SOURCE),$(wildcard orchestrator/builder/fmi_binary/*.c))
FMI_LINK = -L$(dir $(FMI_LOCK)) -l:$(notdir $(FMI_LOCK)) -Wl,-rpath,'$$ORIGIN' -ldl -lpthread
FMI_HEADERS := $(wildcard orchestrator/builder/fmi_binary/*.h)
# The shipped library is compiled by zig's C compiler (PyPI package ziglang, pinned in
# constraints.txt, installed into the venv) for glibc $(FMI_GLIBC): it links against that
# release's symbol versions, so it loads on any x86_64 Linux with glibc >= 2.17 whatever glibc
# the building machine has, and a libc call newer than that fails to link instead of raising
# the floor (docs/fmi_binary.md, "glibc"). FMI_CC=gcc builds for this machine's glibc instead.
FMI_GLIBC := 2.17
ZIG_STAMP := $(VENV)/.ziglang
FMI_CC ?= $(BIN)/python-zig cc -target x86_64-linux-gnu.$(FMI_GLIBC) -g0
COMMA := ,
FMI_WARNINGS := -Wall -Wextra -Werror -Wshadow -Wformat=2 -Wconversion -Wsign-conversion \
	-Wmissing-prototypes -Wstrict-prototypes -Wpointer-arith -Wcast-qual -Wundef -Wvla

.PHONY: install fmus demo test test-unit benchmarks clean chromium fmi-binary fmi-binary-sanitized tbb \
	python-check cc-check debian11-root debian12-root \
	portable-fmus

install: $(STAMP)

fmi-binary: $(FMI_BINARY)

# $(call FMI_COMPILE,<extra flags>,<output>,<sources and libraries>): the sources' hash and fmpy's
# headers come from the venv's Python.
FMI_COMPILE = mkdir -p $(dir $(2)) && \
	hash="$$($(BIN)/python -c 'from orchestrator.builder.fmi_binary import source_hash; print(source_hash())')" && \
	headers="$$($(BIN)/python -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')" && \
	$(FMI_CC) -std=c11 -fPIC -shared $(FMI_WARNINGS) -fvisibility=hidden $(1) \
		-DSONOTRACK_SOURCE_SHA256="\"$$hash\"" -I"$$headers" \
		-o $(2) $(3)

# One line, before anything is compiled, when there is no C compiler to compile with.
cc-check:
	@command -v $(firstword $(FMI_CC)) >/dev/null 2>&1 || { echo "no C compiler: '$(FMI_CC)' not found; \
	install one (Debian: apt-get install gcc) or name it: make FMI_CC=/path/to/cc"; exit 1; }

# Makefile: a change to the compile flags rebuilds it too (the source hash covers only the C).
$(ZIG_STAMP): constraints.txt $(STAMP)
	$(BIN)/python -m pip install --quiet -c constraints.txt ziglang
	touch $@

$(FMI_BINARY): $(FMI_SOURCES) $(FMI_HEADERS) $(FMI_LOCK) Makefile $(STAMP) $(ZIG_STAMP)
	@$(MAKE) --no-print-directory cc-check
	$(call FMI_COMPILE,-O2,$@,$(FMI_SOURCES) $(FMI_LINK))

# It records the hash of all the sources too, so any change rebuilds it.
$(FMI_LOCK): $(FMI_LOCK_SOURCE) $(FMI_SOURCES) $(FMI_HEADERS) Makefile $(STAMP) $(ZIG_STAMP)
	@$(MAKE) --no-print-directory cc-check
	$(call FMI_COMPILE,-O2 -Wl$(COMMA)-soname$(COMMA)$(notdir $@),$@,$< -lpthread)

# Test only: the same sources under AddressSanitizer and UBSan, into FMI_SANITIZED_OUT (the C host
# test builds it into a temporary folder and runs it in an ASan-built host; never put in an FMU).
FMI_SANITIZED_OUT ?= build/sonotrack_fmi2_sanitized.so
fmi-binary-sanitized: FMI_CC = gcc
fmi-binary-sanitized: $(FMI_SOURCES) $(FMI_HEADERS) $(FMI_LOCK) $(STAMP)
	$(call FMI_COMPILE,-O1 -g -fno-omit-frame-pointer -fsanitize=address$(COMMA)undefined \
		-fno-sanitize-recover=undefined,$(FMI_SANITIZED_OUT),$(FMI_SOURCES) $(FMI_LINK))

# PYTHON must be a 3.11 (requires-python in pyproject.toml: the pinned wheels are 3.11's); one
# line with the fix otherwise. A $(VENV) made by another Python (an earlier attempt with the
# wrong one) is removed so that it is made again.
PY_VERSION = import sys; print("%d.%d" % sys.version_info[:2]); sys.exit(sys.version_info[:2] != (3, 11))
python-check:
	@version="$$($(PYTHON) -c '$(PY_VERSION)' 2>/dev/null)" || { echo "sonotrack needs \
	Python 3.11; PYTHON='$(PYTHON)' is $${version:-not a working Python}: install python3.11 \
	(Debian: apt-get install python3.11-venv) or run make PYTHON=/path/to/python3.11"; exit 1; }; \
	if [ -e $(VENV) ]; then \
	  made="$$($(BIN)/python -c '$(PY_VERSION)' 2>/dev/null)"; \
	  if [ "$$made" != "$$version" ]; then \
	    echo "$(VENV) was made by Python $${made:-(broken)}, not $$version: making it again"; \
	    rm -rf $(VENV); \
	  fi; \
	fi

# constraints.txt pins every package to the versions the project was tested with.
$(STAMP): pyproject.toml constraints.txt
	@$(MAKE) --no-print-directory python-check
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -c constraints.txt -e ".[test]"
	touch $(STAMP)

fmus: $(STAMP) $(FMI_BINARY)
	$(BIN)/sonotrack build --out $(FMU_DIR)

# FMUs that carry their own Python runtime (docs/fmi_binary.md, "Portable FMUs"), in a folder of
# their own; strip (binutils) comes with the C compiler on Debian.
PORTABLE_FMU_DIR := build/portable-fmus
portable-fmus: $(STAMP) $(FMI_BINARY)
	$(BIN)/sonotrack build --portable --out $(PORTABLE_FMU_DIR)

demo: fmus
	$(BIN)/sonotrack run $(SCENARIO) --out runs/demo

# Headless Chromium renders the HTML reports in the tests (every figure must load). Installed
# from Debian when we are root and apt works; otherwise those tests say why they fell back to
# checking that every image is embedded data. Never fails the build.
chromium:
	@if command -v chromium >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing Debian chromium for the HTML report tests"; \
	  (DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium \
	    >/dev/null 2>&1 || (apt-get update >/dev/null 2>&1 && \
	    DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends chromium \
	    >/dev/null 2>&1)) || echo "chromium: apt-get install failed; browser checks will skip"; \
	else echo "chromium: not root or no apt-get; browser checks will skip"; fi

# Debian minimal roots with no Python, made once by debootstrap (installed from Debian when we are
# root and apt works; Debian's default mirror) and kept outside the repository, for the tests that
# run FMUs away from this machine's Python: Debian 11 (glibc 2.31) for the FMI binary's glibc floor
# (tests/integration/orchestrator/builder/fmi_binary/test_old_glibc.py), Debian 12 for portable
# FMUs (tests/integration/orchestrator/builder/portable/test_no_python.py). The tests read the
# same variables. Never fails the build: where a root cannot be made, its test says why it
# skipped. $(call DEBIAN_ROOT,<folder>,<suite>,<name>,<what it is for>)
ROOTS_DIR := $(or $(XDG_CACHE_HOME),$(HOME)/.cache)/sonotrack/roots
SONOTRACK_DEBIAN11_ROOT ?= $(ROOTS_DIR)/debian11
SONOTRACK_DEBIAN12_ROOT ?= $(ROOTS_DIR)/debian12
DEBIAN_ROOT = \
	if [ -e "$(1)/.complete" ]; then :; \
	elif [ "$$(id -u)" != 0 ]; then echo "$(3): not root; the $(4) test will skip"; \
	else \
	  if ! command -v debootstrap >/dev/null 2>&1 && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing Debian debootstrap for the $(4) test"; \
	    DEBIAN_FRONTEND=noninteractive apt-get install -y debootstrap >/dev/null 2>&1 || \
	    (apt-get update >/dev/null 2>&1 && \
	    DEBIAN_FRONTEND=noninteractive apt-get install -y debootstrap >/dev/null 2>&1); \
	  fi; \
	  if ! command -v debootstrap >/dev/null 2>&1; then \
	    echo "$(3): debootstrap cannot be installed; the $(4) test will skip"; \
	  else \
	    echo "making a Debian $(2) minimal root in $(1) (once, a few minutes)"; \
	    rm -rf "$(1).partial" && mkdir -p "$(dir $(1))" && \
	    debootstrap --variant=minbase $(2) "$(1).partial" \
	      >"$(1).debootstrap.log" 2>&1 && \
	    rm -rf "$(1)" && mv "$(1).partial" "$(1)" && \
	    touch "$(1)/.complete" || \
	    echo "$(3): debootstrap failed (see $(1).debootstrap.log); the $(4) test will skip"; \
	  fi; \
	fi

debian11-root:
	@$(call DEBIAN_ROOT,$(SONOTRACK_DEBIAN11_ROOT),bullseye,debian11-root,old-glibc)

debian12-root:
	@$(call DEBIAN_ROOT,$(SONOTRACK_DEBIAN12_ROOT),bookworm,debian12-root,portable-FMU)

# ecos (the C++ engine in the ecospy wheel) needs Debian's libtbb12 to start; the ecos tests
# (tests/integration/orchestrator/hosts/test_ecos.py) skip, saying why, where it cannot be installed.
tbb:
	@if /sbin/ldconfig -p 2>/dev/null | grep -q 'libtbb\.so\.12'; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing Debian libtbb12 for the ecos tests"; \
	  (DEBIAN_FRONTEND=noninteractive apt-get install -y libtbb12 >/dev/null 2>&1 || \
	    (apt-get update >/dev/null 2>&1 && \
	    DEBIAN_FRONTEND=noninteractive apt-get install -y libtbb12 >/dev/null 2>&1)) \
	    || echo "libtbb12: apt-get install failed; ecos tests will skip"; \
	else echo "libtbb12: not root or no apt-get; ecos tests will skip"; fi

test: $(STAMP) chromium tbb debian11-root debian12-root $(FMI_BINARY)
	$(BIN)/python -m pytest -q

test-unit: $(STAMP) chromium $(FMI_BINARY)
	$(BIN)/python -m pytest -q -m "not integration"

benchmarks: fmus
	for script in benchmarks/[!_]*.py; do $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) $(FMI_BINARY) $(FMI_LOCK) $(FMU_DIR)/*.fmu $(FMU_DIR)/*.ssp runs .pytest_cache
