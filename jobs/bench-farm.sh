#!/usr/bin/env bash
# The task farm's master measured alone (prints; it is not a test): `divcoll bench-farm` at several rank
# counts (oversubscribed beyond this machine's cores: the synthetic items sleep, so the cores are the
# master's), with paper-scale round sizes and a connector gradient's result size. Writes OUT/farm.csv and
# prints a markdown table; divcoll_post.estimate_paper --farm OUT/farm.csv turns it into the efficiency
# of paper-scale rounds at 64 and 512 ranks.
#   bash jobs/bench-farm.sh [OUT=out/farm] [RANKS="8 16 32"] [ITEM_MS=2] [ITEMS=4000] [extra bench-farm flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/farm}
RANKS=${2:-8 16 32}
ITEM_MS=${3:-2}
ITEMS=${4:-4000}
shift $(($# < 4 ? $# : 4))
source jobs/mpi-env.sh
[ -x build/divcoll ] || bash jobs/build.sh
mkdir -p "$OUT"
csv="$OUT/farm.csv"
echo "ranks,computing,items,item_ms,result_bytes,block,depth,fold,round_s,ideal_s,efficiency,master_cpu_us_per_item,task_us_per_msg,task_us_per_item,result_us_per_msg,result_us_per_item,bytes_per_result,task_msgs_per_round,result_msgs_per_round,fold_us_per_result" >"$csv"
echo "# $(date -u +%FT%TZ), $(nproc) cores, load: $(cut -d' ' -f1-3 /proc/loadavg)" | tee "$OUT/farm.txt"
for n in $RANKS; do
  for block in 1 0; do
    for fold in after during; do
      mpirun --oversubscribe -np "$n" build/divcoll bench-farm --items "$ITEMS" --item-ms "$ITEM_MS" --rounds 3 \
        --block "$block" --fold "$fold" "$@" | tee -a "$OUT/farm.txt" | grep '^csv,' | cut -d, -f2- >>"$csv"
    done
  done
done
/usr/bin/python3 - "$csv" <<'EOF'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| ranks | block | fold | round (s) | ideal (s) | efficiency | master µs/item (task + result) | result µs/message | B/result | result msgs/round | fold µs/result |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    blk = "guided" if r["block"] == "0" else r["block"]
    tr = float(r["task_us_per_item"]) + float(r["result_us_per_item"])
    print(f"| {r['ranks']} | {blk} | {r['fold']} | {float(r['round_s']):.3f} | {float(r['ideal_s']):.3f} | "
          f"{float(r['efficiency']):.0%} | {tr:.2f} ({float(r['task_us_per_item']):.2f} + {float(r['result_us_per_item']):.2f}) | "
          f"{float(r['result_us_per_msg']):.1f} | {float(r['bytes_per_result']):.0f} | {float(r['result_msgs_per_round']):.0f} | "
          f"{float(r['fold_us_per_result']):.2f} |")
EOF
