"""experiments/equilibrium/summary.md from cost.csv and random.csv (standard library only)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
import expkit  # noqa: E402

E = expkit


def cost_section(rows):
    groups = {}
    for r in rows:
        groups.setdefault((r["scene"], r["natural_length"], r["particles"]), {}).setdefault(
            r["integrator"], []).append(r)
    out = []
    for (scene, l0, particles), by in groups.items():
        base = by.get("equilibrium")
        base_cpu = E.median([float(r["cpu_seconds"]) for r in base]) if base else None
        table = []
        for integ, rs in by.items():
            cpu = [float(r["cpu_seconds"]) for r in rs]
            med = E.median(cpu)
            table.append([integ, str(len(rs)), ", ".join(sorted({r["status"] for r in rs})),
                          ", ".join(sorted({r["certificate"] for r in rs})), rs[0]["steps"],
                          rs[0]["factorisations"], rs[0]["stop_factorisations"],
                          E.num(1e3 * med, 3), E.num(1e3 * E.percentile(cpu, 95), 3),
                          E.num(1e3 * max(cpu), 3),
                          E.num(med / base_cpu, 3) + "×" if base_cpu else "—"])
        out.append("**%s, %s particles (L0 = %s m), whole sheet**\n\n" % (scene, particles, l0) +
                   E.md_table(["integrator", "runs", "status", "certificate", "steps",
                               "factorisations", "stop's factorisations", "CPU median (ms)",
                               "p95 (ms)", "max (ms)", "CPU / equilibrium"], table))
    return "\n".join(out)


def random_section(rows):
    out = []
    for scene in ("four_corner", "two_corner"):
        rs = [r for r in rows if r["scene"] == scene]
        if not rs:
            continue
        certified = sum(r["certificate"] == "stable_minimum" and r["status"] == "equilibrium"
                        for r in rs)
        fallback = sum("fell back" in r["message"] or "saddle" in r["message"] for r in rs)
        ref_ok = [r for r in rs if r["reference_status"] == "equilibrium"]
        dist = [float(r["distance_m"]) for r in rs if r["distance_m"] not in ("", None)]
        within = sum(d <= 1e-6 for d in dist)
        out.append([scene, str(len(rs)), "%d (%s %%)" % (certified, E.num(100.0 * certified / len(rs), 3)),
                    str(fallback), str(len(ref_ok)), "%d of %d" % (within, len(dist)),
                    E.sci(max(dist)) if dist else "—",
                    E.num(1e3 * E.median([float(r["cpu_seconds"]) for r in rs]), 3),
                    E.num(1e3 * E.median([float(r["reference_cpu_seconds"]) for r in rs]), 3)])
    if not out:
        return ""
    return E.md_table(["scene", "drapes", "certified equilibria", "fallbacks",
                       "reference (cvode-bdf, rtol 1e-10) settled", "within 1e-6 m of it",
                       "largest distance (m)", "CPU median (ms)", "reference CPU median (ms)"], out)


def build(folder):
    cost = E.read_rows(folder, "cost.csv")
    rand = E.read_rows(folder, "random.csv")
    manifest = E.read_json(folder, "manifest.json")
    sections = [("Cost of one drape (cost.csv)", cost_section(cost)),
                ("Random drapes of Table 3's box (random.csv)", random_section(rand)),
                ("Provenance", E.provenance(manifest) if manifest else "")]
    return "equilibrium: tables", ["cost.csv", "random.csv", "manifest.json"], sections


if __name__ == "__main__":
    E.summary_main("equilibrium", build)
