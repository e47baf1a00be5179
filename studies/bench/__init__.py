"""One-off measurements behind ``results/bench/`` (the benchmarks themselves: ``runners.bench``)."""
