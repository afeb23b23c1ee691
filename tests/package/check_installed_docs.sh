#!/bin/sh
# The installed tree (`cmake --install --prefix /usr`, what the package holds) carries every page of docs/ that
# the shipped configs, the unit, the man pages and the installed pages themselves point to, and each man page
# has EXIT STATUS, FILES and EXAMPLES sections and fits 80 columns as man shows it.
# Usage: check_installed_docs.sh BUILD_DIR. Exit 77 (skipped) without man (package man-db) or without the man
# pages (they need help2man: scripts/setup.sh).
set -eu
build="$1"
command -v man >/dev/null || { echo "SKIP: man is not installed (package man-db)"; exit 77; }
ls "$build"/packaging/man/*.gz >/dev/null 2>&1 || { echo "SKIP: no man pages built (package help2man)"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
DESTDIR="$tmp/root" cmake --install "$build" --prefix /usr >/dev/null
doc="$tmp/root/usr/share/doc/toposlam"

# 1. Every docs/NAME.md, /usr/share/doc/toposlam/NAME.md or (NAME.md) link named by an installed text file.
named="$(grep -rhoE '(docs/|doc/toposlam/|\()[a-z0-9-]+\.md' "$tmp/root/etc" "$tmp/root/usr/lib/systemd" "$doc" \
           "$tmp/root/usr/share/man" 2>/dev/null | sed -E 's|^.*[/(]||' | sort -u)"
for page in $(zcat "$tmp"/root/usr/share/man/man*/*.gz | grep -oE 'doc/toposlam/[a-z0-9-]+\.md' | sed 's|.*/||' | sort -u); do
  named="$named $page"
done
named="$(echo "$named" | tr ' ' '\n' | sed '/^$/d' | sort -u)"
[ -n "$named" ] || fail "no page of docs/ is named anywhere: the search is broken"
missing=""
for page in $named; do [ -f "$doc/$page" ] || missing="$missing $page"; done
[ -z "$missing" ] || fail "named but not installed in /usr/share/doc/toposlam:$missing"
for page in deploy.md config.md cameras.md daemon.md; do [ -f "$doc/$page" ] || fail "no $page"; done
echo "docs: $(echo "$named" | wc -w) pages named, all installed"

# 2. Man pages: the sections, and no line wider than 80 columns.
for page in "$tmp"/root/usr/share/man/man*/*.gz; do
  name="$(basename "$page")"
  for section in "EXIT STATUS" FILES EXAMPLES; do
    zcat "$page" | grep -q "^\.SH \"*$section\"*\$" || fail "$name has no $section section"
  done
  MANWIDTH=80 MAN_KEEP_FORMATTING=0 man -l "$page" 2>/dev/null | col -b >"$tmp/$name.txt"
  wide="$(awk 'length > 80' "$tmp/$name.txt" | wc -l)"
  [ "$wide" = 0 ] || { awk 'length > 80' "$tmp/$name.txt" | head -5; fail "$name: $wide lines wider than 80 columns"; }
  echo "$name: $(wc -l <"$tmp/$name.txt") lines, EXIT STATUS, FILES and EXAMPLES, none wider than 80 columns"
done
echo "installed docs and man pages OK"
