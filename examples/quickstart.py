"""etlcal quickstart: simulate the paper's rig, calibrate it, measure a 2 mm stage move.

Run: python examples/quickstart.py  (needs the etlcal wheel; plots if matplotlib is
installed, to quickstart.png next to the working directory).
"""
import numpy as np

import etlcal

# 1. Data: the paper rig's 15 views (board at 75..2 mm, E_com 80..225 mA) with the
#    paper's noise (0.2 px on pixels, 10 um on the stage, 0.4 mA on the current).
sim = etlcal.simulate.paper_rig(seed=7)
obs = sim.observations
print(f"simulated {len(obs)} views, {obs.point_count} corners; A0 = {sim.a0}")

# 2. Calibrate: errors-in-variables (the default) and the paper's estimator (Eq. 24).
# The simulated lens follows the paper's temperature surface: chosen explicitly, it is
# kept in the calibration and used by `e_com` and `at` below.
paper = etlcal.calibrate(obs, sim.a0, thermal="paper", estimator="paper")
eiv = etlcal.calibrate(obs, sim.a0, thermal="paper")
e = np.linspace(80.0, 225.0, 59)
fx_true = np.polyval(sim.truth.kf_x[::-1], e)
for name, cal in (("paper", paper), ("eiv", eiv)):
    fx = np.polyval(cal.kf_x[::-1], e)
    err = 100 * np.max(np.abs(fx / fx_true - 1))
    print(f"{name:>5}: RMS {cal.rms_px:.3f} px after {cal.iterations} iterations, "
          f"max |fx(E) error| {err:.3f} %, principal point {np.round(cal.principal_point, 1)}")

# 3. Run time: a driver current and a lens temperature give E_com, then K and distortion.
#    Outside the calibrated ranges (27..37 degC here) `at` refuses unless
#    allow_extrapolation=True is asked for.
cam = eiv.at(e_in_ma=150.0, temperature_c=31.0)
e_com = cam.e_com_ma
print(f"E_in 150 mA at 31 degC -> E_com {e_com:.2f} mA")
print("K(E_com) =\n", np.round(cam.camera_matrix, 2))
k, dist = eiv.to_opencv(e_com)
print("OpenCV dist (k1, k2, p1, p2, k3) =", np.round(dist, 5))

# 4. Measure: PnP of the board before and after a 2 mm stage move, at 200 mA.
board = np.array([[1.5 * i, 1.5 * j, 0.0] for j in range(12) for i in range(14)])
rng = np.random.default_rng(0)
poses = []
for z in (8.0, 10.0):
    px = sim.truth.project(board + [0.0, 0.0, z], 200.0) + rng.normal(0.0, 0.2, (len(board), 2))
    poses.append(eiv.solve_pnp(board, px, 200.0))
move = np.linalg.norm(poses[0].displacement_mm(poses[1]))
print(f"measured stage move: {move * 1000:.1f} um (true 2000 um), error {abs(move - 2.0) * 1000:.1f} um")
# One standard deviation per axis, from the pixel noise and the calibration's covariance.
std_um = poses[0].displacement_std_mm(poses[1]) * 1000
print(f"displacement std (x, y, z): {np.round(std_um, 1)} um")

# 5. Plot the focal-length curves, if matplotlib is there.
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib not installed: no plot")
else:
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(e, fx_true, "k-", label="truth fx(E)")
    ax.plot(e, np.polyval(paper.kf_x[::-1], e), "--", label="paper BA")
    ax.plot(e, np.polyval(eiv.kf_x[::-1], e), ":", label="errors-in-variables BA")
    ax.set_xlabel("E_com (mA)")
    ax.set_ylabel("fx (px)")
    ax.legend()
    fig.tight_layout()
    fig.savefig("quickstart.png", dpi=100)
    print("plot written to quickstart.png")
