#!/usr/bin/env bash
# Pages in a real browser: headless Chromium (Debian's package) renders the HTML report and the
# live page; the tests are #[ignore]d in the plain test run because they need the browser.
set -euo pipefail
if ! command -v chromium >/dev/null; then
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
cargo test -p propid --test report_html -- --ignored
