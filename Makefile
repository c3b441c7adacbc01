# Thin wrapper around CMake. The two commands the README names:
#   make demo   installs what is missing, builds, simulates circuits/buck.cir (CSV + PNG)
#   make test   installs what is missing, builds and runs every test: the suite, the suite
#               again under ASan + UBSan, and the netlist parser's fuzzer for 60 s
# Quicker, while developing: make check (the suite only).
#   make report   the benchmark report: padsim against ngspice and SUNDIALS IDA, error against
#                 run time -> docs/benchmarks.md, docs/benchmarks/*.png (about 10 min on 2 cores;
#                 installs libsundials-dev, builds in $(BUILD)-bench; not part of make test)
#   make robustness-report   runs tests/robustness (every case, known failures too) and writes
#                            docs/robustness.md
BUILD ?= build
JOBS ?= 2
DEMO ?= circuits/buck.cir

.PHONY: deps build demo test check test-sanitize fuzz bench report robustness-report clean

deps:
	@scripts/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

demo: build
	@mkdir -p out
	$(BUILD)/src/cli/padsim $(DEMO) -o out/demo.csv --plot out/demo.png --stats
	@echo "waveform: out/demo.csv  plot: out/demo.png"

test: check test-sanitize fuzz

check: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

test-sanitize: deps
	@cmake -S . -B $(BUILD)-sanitize -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPADSIM_SANITIZE=ON >/dev/null
	@cmake --build $(BUILD)-sanitize -j$(JOBS)
	@cd $(BUILD)-sanitize && ctest --output-on-failure -j$(JOBS)

fuzz: deps
	@tests/netlist/run-fuzz.sh 60

bench: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPADSIM_BENCH=ON >/dev/null
	@cmake --build $(BUILD) -j$(JOBS)

robustness-report: build
	@python3 tests/robustness/robustness.py report --padsim $(BUILD)/src/cli/padsim --output docs/robustness.md \
	  --workdir $(BUILD)/robustness-report

report:
	@scripts/install-deps.sh --bench
	@cmake -S . -B $(BUILD)-bench -DCMAKE_BUILD_TYPE=Release -DPADSIM_BENCH=ON >/dev/null
	@cmake --build $(BUILD)-bench -j$(JOBS) --target padsim padae_logical_function_bench
	@cmake --build $(BUILD)-bench -j$(JOBS) --target padae_ida_compare padsim_ida_reference || \
	  echo "make report: the IDA comparison and reference not built (SUNDIALS missing?); the report says so"
	python3 bench/report/run_report.py --build $(BUILD)-bench

clean:
	rm -rf $(BUILD) $(BUILD)-sanitize build-netlist-fuzz out
