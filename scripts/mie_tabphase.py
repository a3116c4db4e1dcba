"""The tabulated phase function both Mitsuba cross-checks use: a 1 um Mie table from
`nephele mie`, resampled at 20001 regular mu nodes from -1 to 1 (Mitsuba's tabphase grid) and
written for nephele as tmp/tab.npz (theta_deg, phase). Smooth enough on that grid that the two
codes' interpolations, linear in mu (Mitsuba) and in theta (nephele), integrate it alike."""
import subprocess
from pathlib import Path

import numpy as np


def regular_mu_table(bin_path: Path, tmp: Path) -> tuple[np.ndarray, np.ndarray]:
    """(theta nodes in degrees, increasing; phase values at them); also writes tmp/tab.npz."""
    subprocess.run([str(bin_path), "mie", "--diameter", "1", "--sizes", "41", "--wavelengths",
                    "400:700:16", "--out", str(tmp / "mie"), "--no-plot"], check=True,
                   capture_output=True)
    mie = np.load(tmp / "mie" / "phase.npz")
    mu_nodes = np.linspace(-1.0, 1.0, 20001)
    theta_nodes = np.degrees(np.arccos(mu_nodes))[::-1]
    theta_nodes[0], theta_nodes[-1] = 0.0, 180.0
    values = np.interp(theta_nodes, mie["theta_deg"], mie["phase"])
    np.savez(tmp / "tab.npz", theta_deg=theta_nodes, phase=values)
    return theta_nodes, values
