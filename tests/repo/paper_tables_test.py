"""benchmarks/paper_tables.json, the paper's tables as transcribed, is self-consistent: every
average is the mean of its three scenes (to the published rounding), and the gaps the readings quote
follow from the tables."""
import json
import sys

ROUNDING = 0.0015  # three published decimals on each of four numbers
t = json.load(open(sys.argv[1] + "/benchmarks/paper_tables.json"))
problems = []
for name in ("table_1_snow", "table_2_rain"):
    for method, scenes in t[name].items():
        for m in ("psnr", "ssim", "lpips"):
            mean = sum(scenes[s][m] for s in ("tanabata", "pool", "factory")) / 3
            if abs(mean - scenes["average"][m]) > ROUNDING:
                problems.append(f"{name} {method} {m}: average {scenes['average'][m]}, mean of scenes {mean:.4f}")
gap = lambda table, a, b: t[table][a]["average"]["psnr"] - t[table][b]["average"]["psnr"]
for table, a, b, quoted in (("table_1_snow", "WeatherGS", "3DGS", 1.77), ("table_2_rain", "WeatherGS", "3DGS", 0.43),
                            ("table_1_snow", "DerainNeRF", "NeRF", 1.78), ("table_2_rain", "DerainNeRF", "NeRF", -1.64)):
    if abs(gap(table, a, b) - quoted) > 0.006:
        problems.append(f"{table}: {a} - {b} = {gap(table, a, b):.3f}, the readings quote {quoted}")
if set(t["table_3_ablation"]) != {"w/o AEF", "w/o LED", "Full"}:
    problems.append("table_3_ablation: expected w/o AEF, w/o LED, Full")
print("\n".join(problems) if problems else "paper_tables.json: averages and quoted gaps consistent")
sys.exit(1 if problems else 0)
