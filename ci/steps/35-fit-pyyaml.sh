#!/usr/bin/env bash
# propid fit's YAML must load as floats in PyYAML (YAML 1.1), as the seed's output did. The test
# is named exactly: a rename makes this step fail, not pass with nothing run.
set -euo pipefail
. ci/lib.sh
python3 -m pip install --quiet --disable-pip-version-check pyyaml
expect_tests 1 cargo test -q -p propid --test fit_cli -- --ignored --exact yaml_numbers_are_floats_to_pyyaml
