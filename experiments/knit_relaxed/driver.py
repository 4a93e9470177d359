"""knit_relaxed: relaxed plain jersey from the yarn-level model's periodic cell, against the
knitting literature's dimensional constants (docs/yarn_model.md, "Periodic cell").

Every run is `knitsim knit --chart plain.chart --set knit.model=yarn --set
knit.boundary=periodic --set knit.stitch_length=L [--set knit.yarn_vertices=N]` with the default
yarn (25 tex cotton, docs/yarn_model.md "Parameters"): one wale x one course of plain jersey,
its rest lengths ramped to L, relaxed with its width and height free; 32 edges per loop
(--quick: 16), which the convergence part shows converged to 1 %.

Parts (column `part` of runs.csv):
  literature   tightness factor sqrt(tex) / l (l in mm) 1.47 and 1.3;
  loop_length  l = 0.8 .. 1.2 x the 1.47 stitch length (--quick: 0.8, 1.0, 1.2);
  convergence  knit.yarn_vertices 8, 16, 32, 64 at the 1.47 stitch length (--quick: 8, 16).

  pattern      the 1 x 1 tuck pattern (repeat KT / KK: a tuck on alternate needles in
               alternate courses) and the 1 x 1 miss pattern (KM / KK) as 2 x 2 cells beside
               plain jersey (K), all at l = 3.4 mm (--quick: 16 edges per loop).
  pull         the relaxed 1.47 cell pulled along the courses and along the wales to 20 %
               strain (--quick: 5 %) in steps of 0.01, the other length free (curves.csv).

Outputs in --out: runs.csv (one row per run), curves.csv (the pulls), manifest.json. Called by run.sh; see README.md.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

TEX = 25.0  # the default yarn's (yarn.tex); the study sets no yarn key


def stitch_length(tightness):
    """l (m) of the default yarn at a tightness factor sqrt(tex) / l, l in mm."""
    return math.sqrt(TEX) / tightness * 1e-3


def main():
    args = expkit.parse_args("knit_relaxed", "knit_relaxed")
    chart = os.path.join(args.out, "plain.chart")
    with open(chart, "w") as f:
        f.write("K\n")
    l0 = stitch_length(1.47)
    n = 16 if args.quick else 32  # vertices per loop: the convergence part shows 32 converged
    plan = [("literature", "tf-%.2f" % tf, stitch_length(tf), n) for tf in (1.47, 1.3)]
    factors = (0.8, 1.0, 1.2) if args.quick else (0.8, 0.9, 1.0, 1.1, 1.2)
    plan += [("loop_length", "l-x%.1f" % f, f * l0, n) for f in factors]
    plan += [("convergence", "n-%d" % n, l0, n) for n in ((8, 16) if args.quick else (8, 16, 32, 64))]
    rows, first = [], None
    for part, label, length, vertices in plan:
        r = expkit.run_knitsim(args.out, "%s-%s" % (part, label), [
            "knit", "--chart", chart, "--set", "knit.model=yarn", "--set",
            "knit.boundary=periodic", "--set", "knit.stitch_length=%.6g" % length, "--set",
            "knit.yarn_vertices=%d" % vertices])
        first = first or r
        c = (r.summary or {}).get("cell", {})
        rows.append(dict(part=part, label=label, stitch_length_m=c.get("stitch_length_m"),
                         tightness_factor=c.get("tightness_factor"), edges_per_wale=vertices,
                         width_m=c.get("width_m"), height_m=c.get("height_m"),
                         courses_per_cm=c.get("courses_per_cm"),
                         wales_per_cm=c.get("wales_per_cm"), K_c=c.get("K_c"),
                         K_w=c.get("K_w"), K_s=c.get("K_s"), R=c.get("R"),
                         clearance_min_over_d=c.get("clearance_min_over_d"),
                         course_length_change_max=c.get("course_length_change_max"),
                         dE_dW_N=c.get("dE_dW_N"), dE_dH_N=c.get("dE_dH_N"),
                         status=c.get("status"), steps=c.get("steps"),
                         cpu_seconds=c.get("cpu_seconds"), dof=c.get("dof")))
    # Tuck and miss patterns beside plain jersey (issue 51 item 3): the repeat's top course
    # (drawn first) holds the tuck or the miss on wale 2 over the held loop of course 0.
    for label, text in (("plain", "K\n"), ("tuck", "KT\nKK\n"), ("miss", "KM\nKK\n")):
        path = os.path.join(args.out, "pattern-%s.chart" % label)
        with open(path, "w") as f:
            f.write(text)
        r = expkit.run_knitsim(args.out, "pattern-" + label, [
            "knit", "--chart", path, "--set", "knit.model=yarn", "--set",
            "knit.boundary=periodic", "--set", "knit.stitch_length=3.4e-3", "--set",
            "knit.yarn_vertices=%d" % n])
        c = (r.summary or {}).get("cell", {})
        loops = c.get("loops") or []
        row = dict(part="pattern", label=label, repeat="/".join(c.get("repeat", [])),
                   stitch_length_m=c.get("stitch_length_m"),
                   tightness_factor=c.get("tightness_factor"), edges_per_wale=n,
                   width_m=c.get("width_m"), height_m=c.get("height_m"),
                   courses_per_cm=c.get("courses_per_cm"), wales_per_cm=c.get("wales_per_cm"),
                   K_c=c.get("K_c"), K_w=c.get("K_w"), K_s=c.get("K_s"), R=c.get("R"),
                   clearance_min_over_d=c.get("clearance_min_over_d"),
                   course_length_change_max=c.get("course_length_change_max"),
                   dE_dW_N=c.get("dE_dW_N"), dE_dH_N=c.get("dE_dH_N"), status=c.get("status"),
                   steps=c.get("steps"), cpu_seconds=c.get("cpu_seconds"), dof=c.get("dof"))
        if loops:
            # the knit loop of course 0, wale 0; the held loop (course 0, wale 1) under the tuck
            # or miss (course 1, wale 1)
            row["knit_loop_height_m"] = loops[0][0]["height_m"]
            row["knit_loop_width_m"] = loops[0][0]["width_m"]
            if len(loops) > 1:
                row["held_loop_height_m"] = loops[0][1]["height_m"]
                row["held_loop_width_m"] = loops[0][1]["width_m"]
                t = loops[1][1]
                row.update(tm_stitch=t["stitch"], tm_width_m=t["width_m"],
                           tm_height_m=t["height_m"], tm_depth_m=t["depth_m"],
                           tm_length_m=t["length_m"], tm_straightness=t["straightness"],
                           # its mean z less that of the knit loop beside it (course 1,
                           # wale 1), in d: < 0 behind (the knit's legs come forward, +z)
                           tm_z_behind_knit_over_d=(t["z_mean_m"] - loops[1][0]["z_mean_m"]) /
                           r.summary["yarn_model"]["diameter_m"])
        rows.append(row)
    # Tensile: the relaxed cell pulled along the courses and along the wales (issue 51 item 4).
    strain = 0.05 if args.quick else 0.2
    curves, pull_failed = [], []
    for direction in ("course", "wale"):
        r = expkit.run_knitsim(args.out, "pull-" + direction, [
            "knit", "--chart", chart, "--set", "knit.model=yarn", "--set",
            "knit.boundary=periodic", "--set", "knit.stitch_length=%.6g" % l0, "--set",
            "knit.yarn_vertices=%d" % n, "--set", "knit.cell_pull=" + direction, "--set",
            "knit.cell_strain=%g" % strain])
        p = (r.summary or {}).get("pull") or {}
        for k, e in enumerate(p.get("strain", [])):
            curves.append(dict(direction=direction, step=k, strain=e,
                               force_per_width_N_per_m=p["force_per_width_N_per_m"][k],
                               reaction_N=p["reaction_N"][k],
                               lateral_strain=p["lateral_strain"][k], status=p["status"][k],
                               steps=p["steps"][k], cpu_seconds=p["cpu_seconds"][k]))
        if not p.get("status") or p["status"][-1] != "equilibrium":
            pull_failed.append(direction)
    expkit.write_csv(os.path.join(args.out, "curves.csv"), curves)
    fields = []  # the pattern rows add their loop columns
    for r in rows:
        fields += [k for k in r if k not in fields]
    expkit.write_csv(os.path.join(args.out, "runs.csv"), rows, fields)
    expkit.write_manifest(args, "knit_relaxed", first, {"tex": TEX, "l_1.47_m": l0})
    expkit.finish(args)
    bad = [r for r in rows if r["status"] != "equilibrium"]
    for r in bad:
        print("knit_relaxed: %s %s ended %s" % (r["part"], r["label"], r["status"]),
              file=sys.stderr)
    for d in pull_failed:
        print("knit_relaxed: the pull along the %ss did not reach its strain" % d, file=sys.stderr)
    print("knit_relaxed: wrote %s/runs.csv, curves.csv" % args.out)
    return 1 if bad or pull_failed else 0


if __name__ == "__main__":
    sys.exit(main())
