# sonotrack: everything a fresh clone needs, from a machine with Python 3.11 and make.
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
FMI_SOURCES := $(wildcard orchestrator/builder/fmi_binary/*.c)
FMI_HEADERS := $(wildcard orchestrator/builder/fmi_binary/*.h)
FMI_CC ?= gcc
COMMA := ,
FMI_WARNINGS := -Wall -Wextra -Werror -Wshadow -Wformat=2 -Wconversion -Wsign-conversion \
	-Wmissing-prototypes -Wstrict-prototypes -Wpointer-arith -Wcast-qual -Wundef -Wvla

.PHONY: install fmus demo test test-unit benchmarks clean chromium fmi-binary fmi-binary-sanitized tbb

install: $(STAMP)

fmi-binary: $(FMI_BINARY)

# $(call FMI_COMPILE,<extra flags>,<output>): the sources' hash and fmpy's headers come from the
# venv's Python.
FMI_COMPILE = mkdir -p $(dir $(2)) && \
	hash="$$($(BIN)/python -c 'from orchestrator.builder.fmi_binary import source_hash; print(source_hash())')" && \
	headers="$$($(BIN)/python -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')" && \
	$(FMI_CC) -std=c11 -fPIC -shared $(FMI_WARNINGS) -fvisibility=hidden $(1) \
		-DSONOTRACK_SOURCE_SHA256="\"$$hash\"" -I"$$headers" \
		-o $(2) $(FMI_SOURCES) -ldl -lpthread

# Makefile: a change to the compile flags rebuilds it too (the source hash covers only the C).
$(FMI_BINARY): $(FMI_SOURCES) $(FMI_HEADERS) Makefile $(STAMP)
	$(call FMI_COMPILE,-O2,$@)

# Test only: the same sources under AddressSanitizer and UBSan, into FMI_SANITIZED_OUT (the C host
# test builds it into a temporary folder and runs it in an ASan-built host; never put in an FMU).
FMI_SANITIZED_OUT ?= build/sonotrack_fmi2_sanitized.so
fmi-binary-sanitized: $(FMI_SOURCES) $(FMI_HEADERS) $(STAMP)
	$(call FMI_COMPILE,-O1 -g -fno-omit-frame-pointer -fsanitize=address$(COMMA)undefined \
		-fno-sanitize-recover=undefined,$(FMI_SANITIZED_OUT))

# constraints.txt pins every package to the versions the project was tested with.
$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade "pip>=24"
	$(BIN)/python -m pip install --quiet -c constraints.txt -e ".[test]"
	touch $(STAMP)

fmus: $(STAMP) $(FMI_BINARY)
	$(BIN)/sonotrack build --out $(FMU_DIR)

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

test: $(STAMP) chromium tbb $(FMI_BINARY)
	$(BIN)/python -m pytest -q

test-unit: $(STAMP) chromium $(FMI_BINARY)
	$(BIN)/python -m pytest -q -m "not integration"

benchmarks: fmus
	for script in benchmarks/[!_]*.py; do $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) $(FMI_BINARY) $(FMU_DIR)/*.fmu $(FMU_DIR)/*.ssp runs .pytest_cache
