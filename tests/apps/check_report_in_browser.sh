#!/usr/bin/env bash
# Browser check of `toposlam report` (ctest label `browser`) on two runs:
#   1. the 84 bundled sample frames (`map`, eval against samples_GT.bmp, report);
#   2. a simulated two-traversal run: `toposlam sim office --route loop2` (short: 2 frames per simulated
#      second), `map` of its frames, `eval` and `report` against its labels.csv (so the rooms strip shows).
# Each page is opened in headless Chromium through chromedriver (webdriver_check.py: WebDriver over HTTP on
# 127.0.0.1), which reads every image's naturalWidth from the rendered DOM and takes a full-page screenshot.
# Fails when
#   - `toposlam report` prints a `report: warning` (e.g. frames it could not read for thumbnails),
#   - the page holds a "no frame" placeholder, fewer <img>/<figure>/<svg> than the run folder calls for,
#     an image the browser could not decode (naturalWidth 0), or no rooms strip for the simulated run,
#   - the page references anything that is not inline (src=/href= to a file or URL),
#   - the screenshot is missing or nearly blank.
# Exits 77 (skipped) when Chromium or chromedriver is not installed (scripts/setup.sh installs both).
# Usage: check_report_in_browser.sh TOPOSLAM SAMPLES_DIR WORK_DIR
set -euo pipefail
toposlam="$1"; samples="$2"; work="$3"
here="$(cd "$(dirname "$0")" && pwd)"

browser=""
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null 2>&1; then browser="$(command -v "$candidate")"; break; fi
done
driver="$(command -v chromedriver || true)"
if [ -z "$browser" ] || [ -z "$driver" ]; then
  echo "skipped: needs chromium and chromedriver (Debian chromium, chromium-driver; scripts/setup.sh)"; exit 77
fi
python=/usr/bin/python3
[ -x "$python" ] || python="$(command -v python3)"

rm -rf "$work"; mkdir -p "$work"

# report RUN TRUTH HTML: writes the page and fails on any `report: warning`.
report() {
  local run="$1" truth="$2" html="$3"
  "$toposlam" report "$run" --truth "$truth" --out "$html" >"$html.log" 2>&1 || { cat "$html.log"; exit 1; }
  if grep -q "report: warning" "$html.log"; then
    cat "$html.log"; echo "FAIL: toposlam report warned (above)"; exit 1
  fi
  if grep -q ">no frame<" "$html"; then echo "FAIL: $html has a 'no frame' thumbnail placeholder"; exit 1; fi
  # Everything must be inline: no src/href pointing anywhere but data: URIs or in-page anchors.
  if grep -Eo '(src|href)="[^"#d][^"]*"' "$html" | grep -v '^[a-z]*="data:'; then
    echo "FAIL: $html references external files (above)"; exit 1
  fi
}

echo "== bundled samples"
"$toposlam" map "images:$samples/samples" --out "$work/samples-run" >"$work/samples-map.log" 2>&1
"$toposlam" eval "$work/samples-run" --truth "$samples/samples_GT.bmp" >"$work/samples-eval.log"
report "$work/samples-run" "$samples/samples_GT.bmp" "$work/samples-report.html"
"$python" "$here/webdriver_check.py" --chromedriver "$driver" --browser "$browser" \
  --page "$work/samples-report.html" --run "$work/samples-run" --screenshot "$work/samples-report.png"

echo "== simulated office, two traversals"
"$toposlam" sim office --route loop2 --fps 2 --progress 0 --out "$work/sim" 2>"$work/sim.log"
"$toposlam" map "images:$work/sim/frames" --out "$work/sim-run" >"$work/sim-map.log" 2>&1
"$toposlam" eval "$work/sim-run" --truth "$work/sim/labels.csv" >"$work/sim-eval.log"
grep -q "2 traversal(s)" "$work/sim-eval.log" || { cat "$work/sim-eval.log"; echo "FAIL: expected 2 traversals"; exit 1; }
report "$work/sim-run" "$work/sim/labels.csv" "$work/sim-report.html"
"$python" "$here/webdriver_check.py" --chromedriver "$driver" --browser "$browser" --expect-rooms \
  --page "$work/sim-report.html" --run "$work/sim-run" --screenshot "$work/sim-report.png"
echo "PASS (screenshots: $work/samples-report.png, $work/sim-report.png)"
