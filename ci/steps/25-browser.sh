#!/usr/bin/env bash
# Pages in a real browser: Debian's Chromium renders the HTML report (headless --dump-dom) and,
# driven by playwright-core (npm; it uses the system Chromium, downloads no browser), the live
# page of `propid demo --live`: live data, the charts, the estimate, and the STOP button. These
# tests are #[ignore]d in the plain test run because they need the browser; here every one of
# them must run and pass.
set -euo pipefail
. ci/lib.sh
if ! command -v chromium >/dev/null; then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
(cd tests/browser && npm install --no-audit --no-fund --silent)
run_ignored propid host-cli/tests/report_html.rs
run_ignored propid host-cli/tests/live_page.rs
