#!/usr/bin/env bash
# Fetches the real DEM the importer tests read (CIG_TEST_REAL_DEM): elev.tif, a small GeoTIFF of
# Luxembourg (EPSG:4326) shipped by Debian's package r-cran-terra. The package is downloaded with
# apt-get and unpacked with dpkg-deb, never installed (R is not needed).
#
# Usage: scripts/fetch-test-data.sh        prints the path of elev.tif on stdout
#        CIG_TEST_REAL_DEM="$(scripts/fetch-test-data.sh)" cargo test -p cig-terrain-io
#
# Idempotent: does nothing but print the path when the file is already there.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
dest="$root/.cache/test-data"
dem="$dest/elev.tif"

if [ -s "$dem" ]; then
    echo "$dem"
    exit 0
fi

for tool in apt-get dpkg-deb; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "fetch-test-data: $tool is unavailable: this script needs a Debian or Ubuntu system" \
             "(it downloads the package r-cran-terra, which ships elev.tif)" >&2
        exit 1
    fi
done

sudo=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        sudo="sudo"
    fi
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
# apt-get download needs only the package lists; refresh them once if the package is unknown.
# (Run as root, apt warns that its _apt user cannot write here: harmless.)
if ! apt-get download r-cran-terra >&2 2>"$work/apt.log"; then
    echo "fetch-test-data: r-cran-terra not in the package lists; running apt-get update" >&2
    $sudo apt-get update -qq >&2
    if ! apt-get download r-cran-terra >&2; then
        echo "fetch-test-data: apt-get download r-cran-terra failed" >&2
        exit 1
    fi
fi
deb="$(ls "$work"/r-cran-terra_*.deb)"
dpkg-deb -x "$deb" "$work/pkg"
src="$work/pkg/usr/lib/R/site-library/terra/ex/elev.tif"
if [ ! -s "$src" ]; then
    echo "fetch-test-data: $(basename "$deb") does not contain usr/lib/R/site-library/terra/ex/elev.tif" >&2
    exit 1
fi
mkdir -p "$dest"
cp "$src" "$dem.tmp"
mv "$dem.tmp" "$dem"
echo "fetch-test-data: $(basename "$deb") -> $dem" >&2
echo "$dem"
