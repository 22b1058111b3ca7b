#!/usr/bin/env bash
# Install the headless browser of the report test (python/tests/test_report_browser.py): Debian's
# chromium, plus fonts so that text in the SVG figures has glyphs. Idempotent; needs root and
# apt-get (CI runs as root). Prints the browser's path.
#
#   bash validation/setup_browser.sh
set -euo pipefail
find_browser() { command -v chromium || command -v chromium-browser || true; }
if [ -z "$(find_browser)" ]; then
    if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
        echo "setup_browser.sh: chromium is missing and cannot be installed here (need root and apt-get)" >&2
        exit 1
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        chromium fonts-dejavu-core >/dev/null
fi
B="$(find_browser)"
[ -n "$B" ] || { echo "setup_browser.sh: chromium not found after installing it" >&2; exit 1; }
"$B" --version >&2 2>/dev/null || true
echo "$B"
