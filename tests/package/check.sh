#!/usr/bin/env bash
# The Debian package, checked as a user and a Debian maintainer would
# (the test command's package stage; docs/packaging.md):
#
#   tests/package/check.sh BUILD_DIR
#
# BUILD_DIR is a release build with everything built. Makes the package
# (cpack -G DEB), unpacks it into a temporary root and runs the installed
# program on the bundled CT (info, mesh, render); checks the desktop entry
# (desktop-file-validate), the MIME types (shared-mime-info compiles them and
# maps *.nii.gz, *.nrrd, *.mha, *.dcm and *.isoscope.json to what the entry
# opens), the manual page (man renders it; every subcommand is in it), that
# `cmake --install` installs the same files, and runs lintian (no errors).
# Prints what it checked; exits non-zero at the first failure.
set -euo pipefail
build=$(cd "${1:?usage: check.sh BUILD_DIR}" && pwd)
src=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d /tmp/isoscope-package-XXXXXX)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "package: FAILED: $*"; exit 1; }

rm -f "$build"/isoscope_*.deb
(cd "$build" && cpack -G DEB >"$tmp/cpack.log" 2>&1) || { cat "$tmp/cpack.log"; fail "cpack"; }
deb=$(ls "$build"/isoscope_*.deb)
echo "package: built $(basename "$deb") ($(du -k "$deb" | cut -f1) KiB)"
dpkg-deb -f "$deb" Depends | sed "s/^/package: depends on /"

root="$tmp/root"
dpkg-deb -x "$deb" "$root"
for f in usr/bin/isoscope usr/lib/isoscope/libisoscope_image.so usr/share/applications/isoscope.desktop usr/share/mime/packages/isoscope.xml \
         usr/share/icons/hicolor/48x48/apps/isoscope.png usr/share/icons/hicolor/256x256/apps/isoscope.png \
         usr/share/man/man1/isoscope.1.gz usr/share/doc/isoscope/copyright usr/share/doc/isoscope/changelog.gz; do
  [[ -s $root/$f ]] || fail "/$f is missing"
done

# The installed program on the bundled CT (it links only system libraries).
exe="$root/usr/bin/isoscope"
"$exe" --version | head -1 | grep -q "^isoscope .*(commit " || fail "isoscope --version names no commit"
echo "package: $("$exe" --version | head -1)"
"$exe" info "$src/datasets/headsq.nhdr" >"$tmp/info.txt" || fail "isoscope info"
grep -q "64 x 64 x 93" "$tmp/info.txt" || fail "isoscope info: unexpected dimensions"
"$exe" mesh "$src/datasets/headsq.nhdr" --iso 1150 -o "$tmp/bone.stl" >/dev/null || fail "isoscope mesh"
"$exe" render "$src/datasets/headsq.nhdr" --iso 500 --iso 1150 --opacity 0.4 --opacity 1 --view left \
  --size 320x240 --ao cone -o "$tmp/head.png" >/dev/null || fail "isoscope render"
[[ $(head -c 8 "$tmp/head.png" | od -An -tx1 | tr -d ' \n') == 89504e470d0a1a0a ]] || fail "render wrote no PNG"
echo "package: the installed isoscope read, meshed and rendered the bundled CT"

# Desktop integration.
desktop-file-validate "$root/usr/share/applications/isoscope.desktop" || fail "desktop entry"
mime="$tmp/mime"
mkdir -p "$mime/packages"
cp /usr/share/mime/packages/freedesktop.org.xml "$root/usr/share/mime/packages/isoscope.xml" "$mime/packages/"
update-mime-database "$mime" >/dev/null 2>&1 || fail "update-mime-database refused the MIME types"
wanted=$(sed -n 's/^MimeType=//p' "$root/usr/share/applications/isoscope.desktop" | tr ';' '\n' | sed '/^$/d')
for pattern in '*.nii.gz' '*.nrrd' '*.mha' '*.dcm' '*.isoscope.json'; do
  type=$(grep -F ":$pattern" "$mime/globs2" | sort -t: -k1 -nr | head -1 | cut -d: -f2)
  grep -qx "$type" <<<"$wanted" || fail "$pattern is $type, which the desktop entry does not open"
done
echo "package: desktop entry valid; *.nii.gz *.nrrd *.mha *.dcm *.isoscope.json open in isoscope"

# The manual page.
MANWIDTH=100 man -l "$root/usr/share/man/man1/isoscope.1.gz" >"$tmp/man.txt" 2>"$tmp/man.err" || fail "man"
for c in info mesh render view pick measure gui; do
  grep -q "^   $c\$" "$tmp/man.txt" || fail "the manual page has no section for '$c'"
done
echo "package: manual page renders ($(wc -l <"$tmp/man.txt") lines, every subcommand)"

# cmake --install installs the same files.
cmake --install "$build" --prefix "$tmp/install/usr" >/dev/null
(cd "$root" && find . -type f | sort) >"$tmp/deb.list"
(cd "$tmp/install" && find . -type f | sort) >"$tmp/install.list"
diff "$tmp/deb.list" "$tmp/install.list" >/dev/null || { diff "$tmp/deb.list" "$tmp/install.list"; fail "cmake --install differs"; }
echo "package: cmake --install installs the same $(wc -l <"$tmp/deb.list") files"

# What a Debian maintainer runs first.
lintian --fail-on error --suppress-tags binary-has-unneeded-section "$deb" >"$tmp/lintian.txt" 2>&1 || {
  cat "$tmp/lintian.txt"; fail "lintian"; }
echo "package: lintian: no errors ($(grep -c '^[WEI]:' "$tmp/lintian.txt" || true) other tags)"
