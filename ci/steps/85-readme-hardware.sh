#!/usr/bin/env bash
# README.md's "With hardware" section, word for word, against the simulated Telega on a socat pty
# pair (tests/readme_hardware.sh): telega check (fails), fix and store, check (ready), a first
# drive with the limits, fit, plan, the planned drive, diagnose, report; STANDBY and zero last.
# About a minute: two runs in real time (a 10 s and a planned ≤ 30 s pattern, each after the soft
# start and the seed's 5 s init).
set -euo pipefail
cargo build --release -q -p propid
bash tests/readme_hardware.sh target/release/propid
