"""The coarse impact from Python: run it, plot the intruder's depth against time, and step a
second copy to look at the bed's pressure mid-impact.

    pip install ./python matplotlib
    python3 examples/python/impact.py out/impact-py impact.png

The first argument is the run's directory, the second the PNG to write.
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import regolith  # noqa: E402

out, png = sys.argv[1], sys.argv[2]
scene = regolith.load_scene("scenes/impact_tipped_coarse.ron")

# 1. A whole run, as `regolith run` makes it, read back as numpy arrays.
run = regolith.run(scene, out)
t, y = run.trajectory["t"], run.trajectory["intruder_y"]
impact = run.summary["impact"]
depth = y[0] - y  # the tip starts at the free surface
print(f"{run}: final depth {impact['final_depth']:.3f} m, stopping time {impact['stopping_time']:.3f} s")

# 2. The same scene stepped from Python to 0.1 s, its points read directly.
sim = regolith.Simulation(scene)
sim.run_until(0.1)
bed, intruder = sim.points("bed"), sim.points("intruder")

fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5), width_ratios=[1, 1.2])
left.plot(t, depth, color="k")
left.axhline(impact["final_depth"], ls="--", color="tab:red", label="final depth (summary.json)")
left.axvline(impact["stopping_time"], ls=":", color="tab:blue", label="stopping time")
left.set(xlabel="time (s)", ylabel="intruder depth (m)", title="depth against time")
left.legend(loc="lower right")
dots = right.scatter(*bed["position"].T, c=bed["pressure"] / 1e3, s=2, cmap="viridis", vmin=0, vmax=20)
right.scatter(*intruder["position"].T, s=2, color="tab:red")
right.set(aspect="equal", xlabel="x (m)", ylabel="y (m)", title=f"bed pressure at t = {sim.time:.3f} s")
fig.colorbar(dots, ax=right, label="pressure (kPa)")
fig.suptitle(f"{scene.name} from Python (regolith {regolith.__version__}, {run.summary['particles']} points)")
fig.tight_layout()
fig.savefig(png, dpi=110)
print(f"wrote {png}")
