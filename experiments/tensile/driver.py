"""Tensile study: knitsim tensile on three charts along wales and courses, loading then unloading.

Charts (24 x 24, written into OUT/charts/): plain jersey; a tuck pattern (a tuck on every fourth
wale from wale 1 in every fourth course from course 2, knit elsewhere); the same pattern with
misses. Each is pulled with the default model (stabilised network, yarn contact on), --gauge-ratio
2, to 20 % in 10 steps and back (--quick: 10 % in 4 steps).

Outputs in --out: curves.csv (every step of every run), runs.csv (one row per run: specimen,
initial stiffness and Poisson ratio from steps 0 to 1, status, cost), manifest.json. Called by
run.sh; see README.md.
"""
import csv
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

SIZE = 24


def chart(kind):
    """The chart's text, top course first (course 0 at the bottom)."""
    rows = []
    for j in range(SIZE):
        row = ""
        for i in range(SIZE):
            special = kind != "plain" and i % 4 == 1 and j % 4 == 2
            row += ("T" if kind == "tuck" else "M") if special else "K"
        rows.append(row)
    return "\n".join(reversed(rows)) + "\n"


def main():
    args = expkit.parse_args("tensile", "tensile")
    steps, strain = (4, 0.1) if args.quick else (10, 0.2)
    os.makedirs(os.path.join(args.out, "charts"), exist_ok=True)
    curves, runs, first = [], [], None
    for kind in ("plain", "tuck", "miss"):
        path = os.path.join(args.out, "charts", kind + ".chart")
        with open(path, "w") as f:
            f.write(chart(kind))
        for direction in ("wale", "course"):
            label = "%s-%s" % (kind, direction)
            r = expkit.run_knitsim(args.out, label, [
                "tensile", "--chart", path, "--direction", direction, "--steps", steps,
                "--strain", strain, "--unload", "--outputs", 0, "--no-pictures"])
            first = first or r
            s = r.summary
            with open(os.path.join(r.folder, "tensile.csv")) as f:
                for row in csv.DictReader(f):
                    curves.append(dict(chart=kind, direction=direction, step=row["step"],
                                       strain=row["strain"], force_per_width_N_per_m=
                                       row["force_per_width_N_per_m"],
                                       lateral_strain=row["lateral_strain"],
                                       energy_J=row["energy_J"], status=row["status"],
                                       newton_steps=row["newton_steps"]))
            runs.append(dict(chart=kind, direction=direction, wales=s["specimen_wales"],
                             courses=s["specimen_courses"], gauge_m=s["gauge_m"],
                             width_m=s["width_m"], status=s["status"],
                             initial_stiffness_N_per_m=s["initial_stiffness_N_per_m"],
                             initial_poisson_ratio=s["initial_poisson_ratio"],
                             newton_steps_per_step=s["newton_steps_per_step"],
                             cpu_seconds=s["cpu_seconds"]))
    expkit.write_csv(os.path.join(args.out, "curves.csv"), curves)
    expkit.write_csv(os.path.join(args.out, "runs.csv"), runs)
    expkit.write_manifest(args, "tensile", first, {"steps": steps, "strain": strain,
                                                   "gauge_ratio": 2, "size": SIZE})
    expkit.finish(args)
    bad = [r for r in runs if r["status"] != "complete"]
    for r in bad:
        print("tensile: %s along the %ss ended %s" % (r["chart"], r["direction"], r["status"]),
              file=sys.stderr)
    print("tensile: wrote %s/{curves,runs}.csv" % args.out)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
