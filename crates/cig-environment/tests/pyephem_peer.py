"""Independent peer for tests/pyephem.rs: PyEphem (libastro: VSOP87 sun, its own
lunar theory, its own delta-T) computes sun and moon positions and rise/set
events for cases read as JSON lines on stdin, one JSON line out per case.

Input line: {"lat": deg, "lon": deg, "alt_m": m, "jd": UTC Julian date,
             "day_start_jd": UTC Julian date}
Exit code 3 (with a message) when the `ephem` package is missing.
"""

import json
import math
import sys

try:
    import ephem
except ImportError:
    print("python package 'ephem' (PyEphem) is not installed", file=sys.stderr)
    sys.exit(3)

DUBLIN_OFFSET = 2415020.0  # ephem.Date counts days from 1899-12-31 12:00 UT


def to_ephem(jd):
    return ephem.Date(jd - DUBLIN_OFFSET)


def to_jd(d):
    return float(d) + DUBLIN_OFFSET


def observer(case, when):
    o = ephem.Observer()
    o.lat = math.radians(case["lat"])
    o.lon = math.radians(case["lon"])
    o.elevation = case["alt_m"]
    o.pressure = 0  # no refraction: geometric topocentric altitudes
    o.date = when
    return o


def first_event(case, body, horizon_deg, use_center, rising):
    start = to_ephem(case["day_start_jd"])
    end_jd = case["day_start_jd"] + 1.0
    o = observer(case, start)
    o.horizon = math.radians(horizon_deg)
    try:
        if rising:
            t = o.next_rising(body, use_center=use_center)
        else:
            t = o.next_setting(body, use_center=use_center)
    except ephem.CircumpolarError:
        return None
    jd = to_jd(t)
    return jd if jd < end_jd else None


def topocentric_fraction(o, moon):
    """Illuminated fraction seen by the observer: phase angle from the topocentric
    elongation psi, i = atan2(R sin psi, D - R cos psi) (Meeus 48.3)."""
    sun = ephem.Sun(o)
    psi = float(ephem.separation(moon, sun))
    r = sun.earth_distance * 149597870.7
    d = moon.earth_distance * 149597870.7
    i = math.atan2(r * math.sin(psi), d - r * math.cos(psi))
    return (1.0 + math.cos(i)) / 2.0


def main():
    for line in sys.stdin:
        line = line.strip()
        if not line:
            continue
        case = json.loads(line)
        o = observer(case, to_ephem(case["jd"]))
        sun = ephem.Sun(o)
        moon = ephem.Moon(o)
        geo_moon = ephem.Moon(to_ephem(case["jd"]))
        out = {
            "sun_alt": math.degrees(sun.alt),
            "sun_az": math.degrees(sun.az),
            "moon_alt": math.degrees(moon.alt),
            "moon_az": math.degrees(moon.az),
            # PyEphem's `phase` (percent lit) is geocentric.
            "moon_fraction_geocentric": geo_moon.phase / 100.0,
            "moon_fraction_topocentric": topocentric_fraction(o, moon),
            "events": {},
        }
        s = ephem.Sun()
        for name, h, rising in [
            ("sunrise", -0.833, True),
            ("sunset", -0.833, False),
            ("civil_dawn", -6.0, True),
            ("civil_dusk", -6.0, False),
            ("nautical_dawn", -12.0, True),
            ("nautical_dusk", -12.0, False),
            ("astronomical_dawn", -18.0, True),
            ("astronomical_dusk", -18.0, False),
        ]:
            out["events"][name] = first_event(case, s, h, True, rising)
        m = ephem.Moon()
        # Upper limb on a horizon 34' below the geometric one (pressure 0).
        out["events"]["moonrise"] = first_event(case, m, -34.0 / 60.0, False, True)
        out["events"]["moonset"] = first_event(case, m, -34.0 / 60.0, False, False)
        print(json.dumps(out))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
