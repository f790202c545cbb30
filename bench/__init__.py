"""Benchmarks of ur_sim_driver; `make bench` runs `python -m bench` and writes out/bench/*.json."""
