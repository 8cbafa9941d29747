"""Figures of the verification report, each a PNG with title, axis units, legend or colour bar.

:func:`write_figures` draws every figure the measured data allows into the output folder and
returns ``name -> (path, caption)``; the Markdown links them, the HTML embeds them.
"""

import numpy as np

from orchestrator.report.matplotlib_agg import pyplot

from .designs import loop_gains, loop_model

__all__ = ["write_figures"]


def _poly(model, s, kp, kd):
    """Characteristic polynomial of the form of ``s`` at (kp, kd) in the form's units."""
    return model.characteristic_polynomial(*loop_gains(s, kp, kd))


def _save(plt, fig, path):
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _stability_region(plt, model, f, path):
    from matplotlib.colors import TwoSlopeNorm

    from .analysis import kp_edge, spectral_radii

    surface, reach, s = f["surface"], f["reachable"], f["settings"]
    ki = surface["ki"]
    edge_max = max((b["kp_routh"] or 0.0) for b in surface["boundaries"])
    kp_axis = np.linspace(0.0, 1.3 * max(edge_max, surface["kps"][-1]), 70)
    kd_axis = np.linspace(0.0, max(6.0, 2.5 * surface["kds"][-1]), 50)
    radius = spectral_radii([_poly(model, s, kp, kd)
                             for kd in kd_axis for kp in kp_axis]).reshape(kd_axis.size, -1)
    unit_kp = loop_gains(s, 1.0, 0.0)[0]
    edge = np.array([kp_edge(model, loop_gains(s, 1.0, kd)[1], ki) / unit_kp
                     for kd in kd_axis[::2]])
    box = f["paper_box"]["box"]
    points = np.array([[p["kp"], p["kd"]] for p in reach["points"]])
    norm = TwoSlopeNorm(vmin=0.9, vcenter=1.0, vmax=1.3)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    for ax, zoom in zip(axes, (False, True)):
        mesh = ax.pcolormesh(kp_axis, kd_axis, np.clip(radius, 0.9, 1.3), shading="auto",
                             cmap="coolwarm", norm=norm)
        ax.plot(edge, kd_axis[::2], color="k", lw=2)
        ax.add_patch(plt.Rectangle((box["kp_min"], box["kd_min"]), box["kp_max"] - box["kp_min"],
                                   box["kd_max"] - box["kd_min"], fill=False, ec="lime", lw=2))
        ax.plot(points[:, 0], points[:, 1], ".", color="darkorange", ms=3)
        ax.set_xlabel("kp [1] (e = v_ref - v_meas)")
        ax.set_ylabel("kd [1]")
        if zoom:
            ax.set_xlim(box["kp_min"] - 0.5, box["kp_max"] + 0.5)
            ax.set_ylim(box["kd_min"] - 0.3, box["kd_max"] + 0.3)
            ax.set_title("zoom on the paper's box (the edge is far to the right)", fontsize=9)
        else:
            ax.set_xlim(kp_axis[0], kp_axis[-1])
            ax.set_title(f"Sampled loop, integral ki = {ki:g} 1/s: stable left of the "
                         "black edge", fontsize=9)
        fig.colorbar(mesh, ax=ax, label="largest closed-loop |z| (clipped to 0.9..1.3)")
    axes[0].plot([], [], color="k", lw=2, label="stability edge |z| = 1 (roots)")
    axes[0].plot([], [], color="lime", lw=2, label="paper's box (mapped to e = r - y)")
    axes[0].plot([], [], ".", color="darkorange", label="reachable fuzzy gains")
    axes[0].legend(fontsize=8, loc="upper right")
    return _save(plt, fig, path)


def _bode(plt, model, f, path):
    import control

    s = f["settings"]
    ki = f["surface"]["ki"]
    omega = np.logspace(-1, np.log10(np.pi / model.period * 0.999), 150)
    fig, (mag_ax, phase_ax) = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True)
    for kp in (s["kp_min"], s["kp_max"]):
        for kd in (s["kd_min"], s["kd_max"]):
            response = control.frequency_response(model.loop_tf(*loop_gains(s, kp, kd)),
                                                  omega)
            magnitude = np.squeeze(response.magnitude)
            phase = np.degrees(np.unwrap(np.squeeze(response.phase)))
            label = f"kp {kp:g}, kd {kd:g}"
            mag_ax.semilogx(omega, 20 * np.log10(magnitude), label=label)
            phase_ax.semilogx(omega, phase, label=label)
    mag_ax.axhline(0.0, color="k", lw=0.8)
    phase_ax.axhline(-180.0, color="k", lw=0.8)
    mag_ax.set_ylabel("|C H| [dB]")
    phase_ax.set_ylabel("phase of C H [deg]")
    phase_ax.set_xlabel("frequency [rad/s] (up to Nyquist)")
    mag_ax.set_title(f"Open loop C(z) H(z) at the surface's corners (T = "
                     f"{1000 * model.period:.0f} ms, integral ki = {ki:g} 1/s)", fontsize=9)
    mag_ax.legend(fontsize=8)
    for ax in (mag_ax, phase_ax):
        ax.grid(alpha=0.3, which="both")
    return _save(plt, fig, path)


def _steps(plt, model, f, path):
    import control

    s = f["settings"]
    times = np.arange(int(round(1.5 / model.period)) + 1) * model.period
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    form = loop_model(model, s)
    for kp in (s["kp_min"], s["kp_max"]):
        for kd in (s["kd_min"], s["kd_max"]):
            y = control.step_response(form.closed_loop_tf(*loop_gains(s, kp, kd)),
                                      times).outputs
            ax.step(times, y, where="post", label=f"FGS-PD frozen kp {kp:g}, kd {kd:g}")
    pid = loop_model(model, dict(s, mode="pid"))
    y = control.step_response(pid.closed_loop_tf(s["pid_kp"], s["pid_kd"], s["pid_ki"]),
                              times).outputs
    ax.step(times, y, where="post", ls="--",
            label=f"PID {s['pid_kp']:g} / {s['pid_ki']:g} 1/s / {s['pid_kd']:g}")
    ax.axhspan(0.95, 1.05, color="0.9", label="+-5 % band")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("rim speed / reference step [1]")
    ax.set_title("Closed-loop step responses (sampled linear model, feedforward on)",
                 fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(plt, fig, path)


def _unit_circle(ax):
    theta = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(theta), np.sin(theta), color="0.5", lw=1, label="unit circle")
    ax.set_aspect("equal")
    ax.set_xlabel("Re z")
    ax.set_ylabel("Im z")
    ax.grid(alpha=0.3)


def _root_locus(plt, model, f, path):
    s = f["settings"]
    edge = max((b["kp_routh"] or 0.0) for b in f["surface"]["boundaries"])
    kps = np.linspace(0.0, 1.3 * max(edge, s["kp_max"]), 160)
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    for ax, kd in zip(axes, (s["kd_min"], s["kd_max"])):
        _unit_circle(ax)
        poles = np.array([np.roots(_poly(model, s, kp, kd)) for kp in kps])
        colours = np.repeat(kps, poles.shape[1])
        scatter = ax.scatter(poles.real.ravel(), poles.imag.ravel(), c=colours, s=5,
                             cmap="plasma")
        box = np.array([np.roots(_poly(model, s, kp, kd))
                        for kp in (s["kp_min"], s["kp_max"])]).ravel()
        ax.plot(box.real, box.imag, "kx", ms=7, label=f"kp = {s['kp_min']:g} and {s['kp_max']:g}")
        ax.set_title(f"Root locus over kp 0..{kps[-1]:.0f}, kd = {kd:g}", fontsize=9)
        ax.legend(fontsize=8, loc="lower left")
        fig.colorbar(scatter, ax=ax, label="kp [1]")
    return _save(plt, fig, path)


def _pole_map(plt, f, path):
    grid = f["surface"]["grid"]
    fig, ax = plt.subplots(figsize=(6.8, 6))
    _unit_circle(ax)
    poles = [(p, g["kp"]) for g in grid for p in g["poles"]]
    xy = np.array([p for p, _ in poles])
    scatter = ax.scatter(xy[:, 0], xy[:, 1], c=[kp for _, kp in poles], cmap="viridis",
                         marker="x", s=18)
    pid = np.array(f["pid"]["poles"])
    ax.plot(pid[:, 0], pid[:, 1], "o", mfc="none", color="tab:red", label="PID baseline")
    fig.colorbar(scatter, ax=ax, label="kp of the grid point [1]")
    ax.set_title("Closed-loop poles over the gain surface grid", fontsize=9)
    ax.legend(fontsize=8, loc="lower left")
    return _save(plt, fig, path)


def _plant_fmu(plt, f, path):
    fs = f["fmu_step"]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 6), sharex=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    t = np.array(fs["times"])
    tf_rim = np.array(fs["tf_rim_speed"])
    top.plot(t, tf_rim, color="k", lw=2, label="transfer function")
    for run in fs["runs"]:
        rim = np.array(run["fmu_rim_speed_left"])
        top.plot(t, rim, "--", label=f"FMU rim_speed_left ({run['label']})")
        bottom.plot(t, 1000 * (rim - tf_rim), label=run["label"])
    top.set_ylabel("rim speed [m/s]")
    top.set_title(f"RobotPlant FMU vs u/V, {fs['voltage_v']:g} V step", fontsize=9)
    top.legend(fontsize=8)
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel("FMU - TF [mm/s]")
    bottom.legend(fontsize=8)
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    return _save(plt, fig, path)


def _closed_loop_fmus(plt, f, path):
    loop = f["closed_loop_fmus"]
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    for p in loop["points"]:
        t = np.array(p["times"])
        line, = ax.plot(t, p["tf_rim_speed"], lw=2, alpha=0.5,
                        label=f"TF {p['mode']} ({p['kp']:g}, {p['kd']:g}, {p['ki']:g})")
        ax.plot(t, p["fmu_rim_speed_left"], "--", color=line.get_color(),
                label="FMUs, rim_speed_left")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("rim speed [m/s]")
    shape = ("step" if loop.get("ramp_m_s2") is None
             else f"ramp at {loop['ramp_m_s2']:g} m/s^2")
    ax.set_title(f"RobotPlant + WheelController FMUs in our master vs closed-loop TF "
                 f"({loop['step_m_s']:g} m/s, {shape})", fontsize=9)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    return _save(plt, fig, path)


def _robustness(plt, f, path):
    r = f["robustness"]
    panels = [(f"{name} (integral ki {r['trim_ki']:g} 1/s)" if name != "pid" else "pid", points)
              for name, points in r["points"].items()]
    panels.append(("fgs_pd, the paper's pure PD", f["robustness_pure_pd"]))
    gains, taus = r["gain_factors"], r["time_constant_factors"]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.2 * len(panels) + 1.5, 3.9),
                             layout="constrained")
    for index, (ax, (name, points)) in enumerate(zip(axes, panels)):
        table = np.full((len(taus), len(gains)), np.nan)
        for p in points:
            i, j = taus.index(p["time_constant_factor"]), gains.index(p["gain_factor"])
            table[i, j] = 100 * p["steady_state_error"] if p["spectral_radius"] < 1 else np.nan
        mesh = ax.imshow(table, origin="lower", cmap="magma_r", vmin=0, vmax=50, aspect="auto")
        for i in range(len(taus)):
            for j in range(len(gains)):
                value = table[i, j]
                text = "unstable" if np.isnan(value) else f"{value:.1f}"
                ax.text(j, i, text, ha="center", va="center", fontsize=7,
                        color="white" if value > 25 else "black")
        ax.set_xticks(range(len(gains)), [f"x{g:g}" for g in gains], fontsize=8)
        ax.set_yticks(range(len(taus)), [f"x{t:g}" for t in taus], fontsize=8)
        ax.set_xlabel("plant DC gain factor")
        if index == 0:
            ax.set_ylabel("time-constant factor")
        ax.set_title(name, fontsize=9)
    fig.colorbar(mesh, ax=list(axes), label="steady-state error [% of reference]")
    fig.suptitle("Steady-state wheel-speed error on wheels unlike RobotPlant's (white: unstable)",
                 fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _gain_factor_edges(plt, f, path):
    edges = f["gain_factor_edges"]
    taus = np.array(edges["time_constant_factors"])
    required = f["requirements_grid"]
    fig, ax = plt.subplots(figsize=(9.0, 4.6))
    low_g, high_g = min(required["gain_factors"]), max(required["gain_factors"])
    low_t, high_t = min(required["time_constant_factors"]), max(required["time_constant_factors"])
    ax.fill_between([low_t, high_t], low_g, high_g, color="tab:green", alpha=0.12,
                    label=f"required: gain x{low_g:g}..x{high_g:g}, tau x{low_t:g}..x{high_t:g}")
    for g in required["finding_gain_factors"]:
        ax.axhline(g, color="tab:red", ls="--", lw=1, label=f"finding: gain x{g:g}")
    styles = {"fgs_pd": "-", "pd": "--", "pid": ":"}
    for s in edges["sets"]:
        upper = np.array([e["upper"] if e["nominal_stable"] else np.nan for e in s["edges"]])
        label = f"{s['controller']} (kp {s['kp']:g}, kd {s['kd']:g}, ki {s['ki']:g})"
        ax.plot(taus, upper, styles.get(s["controller"], "-"), marker=".", label=label)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log", base=2)
    ax.set_xticks([0.5, 0.71, 1, 1.41, 2], ["x0.5", "x0.71", "x1", "x1.41", "x2"])
    ticks = [2.0 ** k for k in range(-2, 6)]
    ax.set_yticks(ticks, [f"x{t:g}" for t in ticks])
    ax.set_xlabel("plant time-constant factor")
    ax.set_ylabel("largest stable plant DC-gain factor")
    ax.set_title("Stable up to this plant gain (above a line: unstable); T = "
                 f"{1000 * f['model']['period_s']:g} ms", fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return _save(plt, fig, path)


def write_figures(model, figures, out_dir):
    """Draw every figure into ``out_dir``; return ``name -> (path, caption)``."""
    plt = pyplot()
    plan = [
        ("stability_region", lambda p: _stability_region(plt, model, figures, p),
         "Stability region of the sampled loop in (kp, kd), with the paper's gain box and the "
         "gains the fuzzy scheduler can reach."),
        ("bode_corners", lambda p: _bode(plt, model, figures, p),
         "Bode plots of the open loop at the four corners of the gain surface."),
        ("step_responses", lambda p: _steps(plt, model, figures, p),
         "Closed-loop reference steps at the surface's corners and for the PID."),
        ("root_locus", lambda p: _root_locus(plt, model, figures, p),
         "Root locus over kp at the smallest and largest kd."),
        ("pole_map", lambda p: _pole_map(plt, figures, p),
         "Closed-loop poles at every grid point, coloured by kp."),
        ("robustness", lambda p: _robustness(plt, figures, p),
         "Steady-state error per controller on the plant grid (unst. = unstable)."),
        ("gain_factor_edges", lambda p: _gain_factor_edges(plt, figures, p),
         "Largest stable plant DC-gain factor of each frozen gain set against the plant's "
         "time-constant factor, with the required region and the x4 finding."),
    ]
    if figures.get("fmu_step"):
        plan.append(("fmu_vs_tf", lambda p: _plant_fmu(plt, figures, p),
                     "Built RobotPlant FMU against the transfer function."))
    if figures.get("closed_loop_fmus"):
        plan.append(("closed_loop_fmus", lambda p: _closed_loop_fmus(plt, figures, p),
                     "RobotPlant + WheelController FMUs against the closed-loop TF."))
    written = {}
    for name, draw, caption in plan:
        written[name] = (draw(out_dir / f"{name}.png"), caption)
    return written
