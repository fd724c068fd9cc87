"""Medians and best-of ratios of bench/sim/side_by_side.sh's interleaved pairs (now / base):
harness throughput (env-steps/s, higher is faster) and task time (ns per env-step, lower is
faster). Writes DIR/summary.csv and prints it."""
import collections
import csv
import statistics as st
import sys

out = sys.argv[1]
rows = []
h = collections.defaultdict(lambda: {"base": [], "now": []})
for r in csv.DictReader(open(f"{out}/harness.csv")):
    v = float(r["env_steps_per_s"])
    if v > 0:
        h[(r["case"], r["envs"], r["threads"])][r["side"]].append(v)
for k, v in h.items():
    if v["base"] and v["now"]:
        rows.append(("harness_env_steps_per_s", *k, st.median(v["base"]), st.median(v["now"]), st.median(v["now"]) / st.median(v["base"]),
                     max(v["now"]) / max(v["base"])))
t = collections.defaultdict(lambda: {"base": [], "now": []})
for r in csv.DictReader(open(f"{out}/task.csv")):
    t[(f"{r['task']}/{r['controller'] or '-'}/{r['backend']}", r["envs"], r["threads"])][r["side"]].append(float(r["ns_per_env_step"]))
for k, v in t.items():
    if v["base"] and v["now"]:
        rows.append(("task_ns_per_env_step", *k, st.median(v["base"]), st.median(v["now"]), st.median(v["now"]) / st.median(v["base"]),
                     min(v["now"]) / min(v["base"])))
with open(f"{out}/summary.csv", "w") as f:
    f.write("measure,case,envs,threads,base_median,now_median,ratio_median,ratio_best\n")
    for r in rows:
        f.write("%s,%s,%s,%s,%.4g,%.4g,%.4f,%.4f\n" % r)
print(open(f"{out}/summary.csv").read())
