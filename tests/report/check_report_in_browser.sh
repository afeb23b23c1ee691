#!/usr/bin/env bash
# Browser check of `toposlam report` (ctest label `browser`): maps the 84 bundled sample frames, writes the
# HTML report with the loop-closure ground truth, renders it in headless Chromium and fails when
#   - the report's inline script does not report `images-ok N` (an <img> failed to decode or load), or
#   - the page references anything that is not inline (src=/href= to a file or URL), or
#   - the screenshot is missing or implausibly small.
# Exits 77 (skipped) when Chromium is not installed. Usage: check_report_in_browser.sh TOPOSLAM SAMPLES_DIR WORK_DIR
set -euo pipefail
toposlam="$1"; samples="$2"; work="$3"

browser=""
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null 2>&1; then browser="$candidate"; break; fi
done
if [ -z "$browser" ]; then echo "skipped: no chromium installed (scripts/setup.sh installs it)"; exit 77; fi

rm -rf "$work"; mkdir -p "$work"
"$toposlam" map "images:$samples/samples" --out "$work/run" >"$work/map.log"
"$toposlam" report "$work/run" --truth "$samples/samples_GT.bmp" --frames "$samples/samples" --out "$work/report.html"

# Everything must be inline: no src/href pointing anywhere but data: URIs or in-page anchors.
if grep -Eo '(src|href)="[^"#d][^"]*"' "$work/report.html" | grep -v '^[a-z]*="data:' ; then
  echo "FAIL: the report references external files (above)"; exit 1
fi

flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --hide-scrollbars)
profile="$(mktemp -d)"; trap 'rm -rf "$profile" "$profile-2"' EXIT
timeout 120 "$browser" "${flags[@]}" --user-data-dir="$profile" --virtual-time-budget=10000 --dump-dom \
  "file://$work/report.html" >"$work/dom.html" 2>"$work/chromium-dom.log" || true
marker="$(grep -Eo 'id="image-check">[^<]*' "$work/dom.html" | sed 's/.*>//' || true)"
echo "image check: ${marker:-<none>}"
case "$marker" in
  images-ok\ [1-9]*) ;;
  *) echo "FAIL: expected 'images-ok N' from the page's script (see $work/dom.html, $work/chromium-dom.log)"; exit 1 ;;
esac

mkdir -p "$profile-2"
timeout 120 "$browser" "${flags[@]}" --user-data-dir="$profile-2" --screenshot="$work/report.png" \
  --window-size=1400,3000 "file://$work/report.html" >"$work/chromium-shot.log" 2>&1 || true
size=$(stat -c %s "$work/report.png" 2>/dev/null || echo 0)
echo "screenshot: $work/report.png ($size bytes)"
if [ "$size" -lt 50000 ]; then echo "FAIL: screenshot missing or nearly blank"; exit 1; fi
echo "PASS"
