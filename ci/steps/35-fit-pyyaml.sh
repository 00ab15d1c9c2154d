#!/usr/bin/env bash
# propid fit's YAML must load as floats in PyYAML (YAML 1.1), as the seed's output did.
set -euo pipefail
python3 -m pip install --quiet --disable-pip-version-check pyyaml
cargo test -q -p propid --test fit_cli -- --ignored yaml_numbers_are_floats_to_pyyaml
