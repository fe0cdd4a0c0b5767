#!/usr/bin/python3
"""qnavd_report.py LOG.jsonl OUT_DIR: the demo's view of a qnavd mission on the sim backend.

Reads qnavd's JSON log (one line per tile and per event), prints a per-tile table of every repeat
pass (estimate vs the simulator's true node, side vs the true side, cross-track vs the true offset)
and a summary per pass, and writes qnavd_mission.png (the track in the route's frame against the
truth, the node estimate coloured by its belief against the true node, the cross-track against the
truth; scripts/qnav_plot.py's style: metres on the axes, legends beside the data). A vo
pass (the rover on the Mars yard) is summarised from its "vo" lines: pairs, visual steps, the VO
pose's end error against the simulator's truth, and qnavd_vo.png (the VO track over the true one).
Truth comes from the sim backend (truth_along_m / truth_lateral_m in each tile line); the true node
is the taught node nearest along the route, as `qnav route eval` scores it. Exit 1 when the log
holds no repeat tile.
"""
import json
import sys


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    tiles, events, records = [], [], []
    with open(sys.argv[1]) as f:
        for line in f:
            line = line.strip()
            if not line.startswith("{"):
                continue
            rec = json.loads(line)
            records.append(rec)
            (tiles if rec.get("event") == "tile" else events).append(rec)
    vo = [e for e in events if e.get("event") == "vo"]
    taught = [t["truth_along_m"] for t in tiles if t["mode"] == "teach"]
    # A pass: the repeat tiles between two mode commands (a closed-loop pass, sim.pass.closed_loop,
    # has no constant offset: each tile is judged against its own true offset).
    passes, cur = [], None
    for t in records:
        if t.get("event") == "mode":
            cur = None
            continue
        if t.get("event") != "tile":
            continue
        if t["mode"] != "repeat":
            cur = None
            continue
        if cur is None or cur["reverse"] != t["reverse"]:
            cur = {"reverse": t["reverse"], "lateral": t["truth_lateral_m"], "tiles": []}
            passes.append(cur)
        cur["tiles"].append(t)
    if not passes or not taught:
        print("qnavd_report: no teach and repeat tiles in the log", file=sys.stderr)
        return 1
    deadband = 1.0
    print(f"taught route: {len(taught)} nodes")
    print("pass  dir      offset_m  tile  true  est   p      status         side       true_side  cross_track_m  sigma_m  latency_ms")
    summary = []
    for k, p in enumerate(passes, 1):
        n = w1 = decided = side_ok = 0
        for i, t in enumerate(p["tiles"]):
            truth = min(range(len(taught)), key=lambda j: abs(taught[j] - t["truth_along_m"]))
            lat = t["truth_lateral_m"]
            want = "on_route" if abs(lat) <= deadband else ("starboard" if (lat > 0) != p["reverse"] else "port")
            true_ct = -lat if p["reverse"] else lat
            print(f"{k:4d}  {'reverse' if p['reverse'] else 'forward':7s}  {lat:8.1f}  {t['seq']:4d}  {truth:4d}  {t['estimate']:4d}  "
                  f"{t['p']:.3f}  {t['status']:13s}  {t['side']:9s}  {want:9s}  {t['cross_track_m']:7.2f} ({true_ct:6.2f})  "
                  f"{t['sigma_m']:7.2f}  {t['latency_ms']:8.2f}")
            if i < 2:
                continue  # warm-up: the belief starts uniform (as `qnav route eval` scores)
            n += 1
            w1 += abs(t["estimate"] - truth) <= 1
            if want != "on_route" and t["side"] != "unknown":
                decided += 1
                side_ok += t["side"] == want
        summary.append((k, p, n, w1, decided, side_ok))
    print()
    for k, p, n, w1, decided, side_ok in summary:
        print(f"pass {k} ({'reverse' if p['reverse'] else 'forward'}, offset {p['lateral']:+.1f} m): {n} tiles scored, "
              f"node within +/-1 {100.0 * w1 / max(n, 1):.1f} %, side correct {side_ok}/{decided} decided")
    lat = sorted(t["latency_ms"] for p in passes for t in p["tiles"])
    q = lambda f: lat[min(len(lat) - 1, int(f * len(lat)))]
    print(f"last scanline -> guidance queued for CAN: p50 {q(0.5):.1f} ms, p99 {q(0.99):.1f} ms, max {lat[-1]:.1f} ms over {len(lat)} tiles")
    for e in events:
        if e.get("event") == "stopped":
            print(f"qnavd process: {e['wall_s']:.1f} s wall, {e['cpu_s']:.1f} s CPU ({e['cpu_load_pct']:.0f} % of one core), "
                  f"peak RSS {e['max_rss_kb'] / 1024:.1f} MB, {e['deadline_misses']} deadline misses, {e['software_faults']} software faults")
    refused = [e for e in events if e.get("event") == "mode" and e.get("refused")]
    print(f"mode commands: {sum(1 for e in events if e.get('event') == 'mode')}, refused {len(refused)}")
    if vo:
        last = vo[-1]
        err = ((last["north_m"] - last["truth_north_m"]) ** 2 + (last["east_m"] - last["truth_east_m"]) ** 2) ** 0.5
        path = max(last["truth_path_m"], 1e-9)
        lat = sorted(e["latency_ms"] for e in vo)
        print(f"vo pass (rover on the Mars yard): {len(vo)} stereo pairs, {sum(1 for e in vo if e['visual'])} visual steps, "
              f"{path:.2f} m driven, end error {err * 100:.1f} cm ({100.0 * err / path:.2f} % of the path); "
              f"pair -> VO_STEP queued: p50 {lat[len(lat) // 2]:.1f} ms, max {lat[-1]:.1f} ms")
    try:
        sys.path.insert(0, __import__("os").path.dirname(__import__("os").path.abspath(__file__)))
        from qnav_plot import axes_labels, colour_bar, legend_outside, north_arrow, plt
    except ImportError:
        print("(matplotlib missing: no plot)")
        return 0
    # The mission: (a) the track in the route's frame, true and as qnavd estimated it (the estimated
    # node's taught along-route position, the cross-track it reported); (b) the node estimate against
    # the true node, coloured by the belief of the estimate; (c) the cross-track against the truth.
    fig, axes = plt.subplots(3, 1, figsize=(11, 10.5))
    cmap = plt.get_cmap("viridis")
    markers = "osD^v<>"
    sc = None
    for k, p, *_ in summary:
        seq = [t["seq"] for t in p["tiles"]]
        truth = [min(range(len(taught)), key=lambda j: abs(taught[j] - t["truth_along_m"])) for t in p["tiles"]]
        label = f"pass {k} {'rev' if p['reverse'] else 'fwd'} {p['lateral']:+.0f} m"
        mk = markers[(k - 1) % len(markers)]
        # (a) lateral position in the route's frame (+ starboard of the taught direction): the
        # reported cross-track is relative to the vehicle's heading, reversed on a reverse pass.
        sgn = -1.0 if p["reverse"] else 1.0
        axes[0].plot([t["truth_along_m"] for t in p["tiles"]], [t["truth_lateral_m"] for t in p["tiles"]], "k-", lw=3, alpha=0.25)
        trk = [t for t in p["tiles"] if t["status"] == "tracking"]
        other = [t for t in p["tiles"] if t["status"] != "tracking"]
        line = axes[0].plot([taught[min(t["estimate"], len(taught) - 1)] for t in trk], [sgn * t["cross_track_m"] for t in trk],
                            mk, ms=4, label=label)[0]
        if other:
            axes[0].plot([taught[min(t["estimate"], len(taught) - 1)] for t in other], [sgn * t["cross_track_m"] for t in other],
                         mk, ms=6, mfc="none", color=line.get_color(), label=f"pass {k}: not tracking ({len(other)})")
        axes[1].plot(seq, truth, "k-", lw=3, alpha=0.25)
        sc = axes[1].scatter(seq, [t["estimate"] for t in p["tiles"]], c=[t["p"] for t in p["tiles"]], cmap=cmap, vmin=0.0, vmax=1.0,
                             marker=mk, s=18, edgecolors="none")
        axes[1].plot([], [], mk, color="0.3", ms=4, label=label)
        axes[2].plot(seq, [-t["truth_lateral_m"] if p["reverse"] else t["truth_lateral_m"] for t in p["tiles"]], "k-", lw=3, alpha=0.25)
        # Tracking tiles filled with their sigma; the others (hold course, dead-reckoned, route end)
        # hollow: their cross-track is not a fix the autopilot should steer by.
        eb = axes[2].errorbar([t["seq"] for t in trk], [t["cross_track_m"] for t in trk], yerr=[min(t["sigma_m"], 50) for t in trk],
                              fmt=mk, ms=4, color=line.get_color(), label=label)
        if other:
            axes[2].plot([t["seq"] for t in other], [t["cross_track_m"] for t in other], mk, ms=6, mfc="none",
                         color=eb[0].get_color(), label=f"pass {k}: not tracking ({len(other)})")
    axes[0].plot([], [], "k-", lw=3, alpha=0.25, label="truth (simulator)")
    axes_labels(axes[0], "along the taught route m", "lateral m (+ starboard of route)")
    axes[0].set_title("(a) track in the route's frame (axes not to scale)")
    legend_outside(axes[0])
    axes_labels(axes[1], "tile sequence number", "route node", integer_x=True)
    axes[1].set_title("(b) node estimate (grey: true node), coloured by the belief of the estimate")
    axes[1].plot([], [], "k-", lw=3, alpha=0.25, label="truth (simulator)")
    legend_outside(axes[1])
    axes_labels(axes[2], "tile sequence number", "cross-track m (+ starboard)", integer_x=True)
    axes[2].set_title("(c) cross-track reported (bars: its sigma) against the truth (grey)")
    legend_outside(axes[2])
    fig.suptitle("qnavd on the simulated vehicle: the mission from its log, against the simulator's truth")
    # Legends right of the panels; (b)'s colour bar right of its legend: nothing over the data.
    fig.tight_layout(rect=(0, 0, 0.9, 0.97))
    if sc is not None:
        b = axes[1].get_position()
        cax = fig.add_axes([0.9, b.y0, 0.014, b.height])
        colour_bar(fig, sc, None, "belief p(estimate)", cax=cax)
    out = sys.argv[2] + "/qnavd_mission.png"
    fig.savefig(out, dpi=90)
    print(f"plot: {out}")
    if vo:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
        ax.plot([e["truth_east_m"] for e in vo], [e["truth_north_m"] for e in vo], "k-", lw=4, alpha=0.25, label="truth (simulator)")
        ax.plot([e["east_m"] for e in vo], [e["north_m"] for e in vo], "o-", ms=3, label="qnavd visual odometry")
        axes_labels(ax, "east m (stretched: the rover wanders a few cm)", "north m")
        ax.set_title("track (north up)")
        legend_outside(ax, where="below", ncol=2)
        north_arrow(ax)
        errs = [100.0 * ((e["north_m"] - e["truth_north_m"]) ** 2 + (e["east_m"] - e["truth_east_m"]) ** 2) ** 0.5 for e in vo]
        ax2.plot([e["truth_path_m"] for e in vo], errs, "o-", ms=3)
        axes_labels(ax2, "path driven m", "horizontal position error cm")
        ax2.set_title("error against the simulator's truth")
        ax2.set_ylim(bottom=0)
        fig.suptitle("qnavd vo mode: the rover's track from its stereo pairs (from the daemon's log)")
        fig.tight_layout()
        out = sys.argv[2] + "/qnavd_vo.png"
        fig.savefig(out, dpi=90)
        print(f"plot: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
