"""Figures analogous to the paper's Figs. 4-7 from the shipped hexacopter data (docs/figures/).

Fig. 4-6: pitch, roll and yaw (heading and yaw rate) of one healthy, one rotor-1 and one rotor-2 record
(severe turbulence, first flying record of each), failure at 10 s (dashed). Fig. 7: variance over 10 s windows updated every 0.1 s.
Run from the repository root: ``python docs/scripts/hexacopter_figures.py``.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from tsfdi.datasets import load_hexacopter  # noqa: E402

OUT = Path(__file__).resolve().parents[1] / "figures"
COLORS = {"healthy": "k", "rotor1": "tab:red", "rotor2": "tab:green"}


def pick(ds, state, turbulence="severe"):
    sel = ds.where((ds.state == state) & (ds.turbulence == turbulence) & ~ds.lost_control, drop=True)
    return sel.isel(record=0)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    ds = load_hexacopter()
    recs = {s: pick(ds, s) for s in COLORS}
    for fig_no, name in [(4, "pitch"), (5, "roll"), (6, "yaw")]:
        rows = 2 if name == "yaw" else 1
        fig, axes = plt.subplots(rows, 1, figsize=(7, 3.2 * rows), sharex=True, squeeze=False)
        ax = axes[0, 0]
        for s, r in recs.items():
            ax.plot(r.time, np.degrees(r[name]), color=COLORS[s], lw=0.8, label=s)
        ax.axvline(10.0, ls="--", color="gray")
        ax.set_ylabel(f"{name} (deg)")
        ax.set_title(f"Fig. {fig_no} analogue: {name}, 5 m/s, severe turbulence")
        ax.legend(loc="best", fontsize=8)
        if name == "yaw":  # the heading is unwrapped: also show the yaw rate
            ax = axes[1, 0]
            for s, r in recs.items():
                ax.plot(r.time, r["r"], color=COLORS[s], lw=0.6, label=s)
            ax.axvline(10.0, ls="--", color="gray")
            ax.set_ylabel("yaw rate r (rad/s)")
        axes[-1, 0].set_xlabel("time (s)")
        fig.tight_layout()
        fig.savefig(OUT / f"hexacopter_fig{fig_no}_{name}.png", dpi=120)
        plt.close(fig)
    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for ax, name in zip(axes, ["roll", "pitch", "yaw"]):
        for s, r in recs.items():
            x = r[name].to_pandas()
            rv = x.rolling(1000).var().iloc[::10]
            ax.semilogy(rv.index, rv.values, color=COLORS[s], lw=0.9, label=s)
        ax.axvline(10.0, ls="--", color="gray")
        ax.set_ylabel(f"var {name} (rad$^2$)")
    axes[0].legend(fontsize=8)
    axes[0].set_title("Fig. 7 analogue: variance over 10 s windows every 0.1 s (severe)")
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(OUT / "hexacopter_fig7_rolling_variance.png", dpi=120)
    plt.close(fig)
    print("wrote", sorted(p.name for p in OUT.glob("hexacopter_*.png")))


if __name__ == "__main__":
    main()
