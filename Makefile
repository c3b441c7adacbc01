# Thin wrapper around CMake. The two commands the README names:
#   make demo   installs what is missing, builds, simulates circuits/buck.cir (CSV + PNG)
#   make test   installs what is missing, builds and runs every test
BUILD ?= build
JOBS ?= 2
DEMO ?= circuits/buck.cir

.PHONY: deps build demo test test-sanitize bench clean

deps:
	@scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

demo: build
	@mkdir -p out
	$(BUILD)/src/cli/padsim $(DEMO) -o out/demo.csv --plot out/demo.png --stats
	@echo "waveform: out/demo.csv  plot: out/demo.png"

test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

test-sanitize: deps
	@cmake -S . -B $(BUILD)-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPADSIM_SANITIZE=ON >/dev/null
	@cmake --build $(BUILD)-sanitize -j$(JOBS)
	@cd $(BUILD)-sanitize && ctest --output-on-failure -j$(JOBS)

bench: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPADSIM_BENCH=ON >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

clean:
	rm -rf $(BUILD) $(BUILD)-sanitize out
