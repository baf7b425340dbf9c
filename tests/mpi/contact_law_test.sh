#!/usr/bin/env bash
# run.contact = no_slip on the tiny preset (2 ranks), agents to deploy:
# - the run stores the key, its results differ from coulomb's (the law reaches every stage's scenes);
# - `divcoll export` of an agent alone and of pairs writes scenes whose env/contact is no_slip (with ice's
#   kappa_ns 1/3) and whose simulation reproduces the stored travel bit for bit;
# - --from refuses to reuse a base run made under another contact law.
# Usage: contact_law_test.sh DIVCOLL SOURCE_DIR
set -euo pipefail
D=$1 SRC=$2
source "$SRC/jobs/mpi-env.sh"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
fail() { echo "FAILED: $*"; exit 1; }
CFG=$SRC/configs/tiny.toml
BASE=('run.stages=["agents","connectors","deploy"]' 'connectors.kinds=["weak_diverse"]' run.progress_every_s=0)

mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" run.contact=no_slip --out "$W/ns.h5" > /dev/null
mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" --out "$W/cb.h5" > /dev/null
"$D" export "$W/ns.h5" --what alone --env ice --agent 1 --out "$W/a.h5" > /dev/null
"$D" export "$W/ns.h5" --what pair --env gap --type weak_diverse@diverse --pair 1 --out "$W/p.h5" > /dev/null
"$D" export "$W/ns.h5" --what pair --env ice --type weak_diverse@diverse --pair 2 --out "$W/q.h5" > /dev/null
for x in a p q; do
  "$D" simulate --scene "$W/$x.h5" --steps 200 --out "$W/${x}_traj.h5" > /dev/null
done
/usr/bin/python3 - "$W" <<'PY' || fail "no_slip run, export and simulate"
import sys, h5py
w = sys.argv[1]
ns, cb = h5py.File(f"{w}/ns.h5", "r"), h5py.File(f"{w}/cb.h5", "r")
cfg = ns.attrs["config"]
cfg = cfg.decode() if isinstance(cfg, bytes) else cfg
assert 'contact = "no_slip"' in cfg, "the run file's config does not record run.contact"
for d in ["agents/final/params", "deploy/agents/travel_u", "deploy/collectives/travel_u"]:
    if d in ns:
        assert ns[d][()].tobytes() != cb[d][()].tobytes(), f"{d}: no_slip gave coulomb's bits"
envs = ns["deploy"].attrs["environments"]
envs = (envs.decode() if isinstance(envs, bytes) else envs).split(",")
types = ns["deploy"].attrs["types"]
t = (types.decode() if isinstance(types, bytes) else types).split(",").index("weak_diverse@diverse")
def attr(f, a):
    v = h5py.File(f, "r")["env"].attrs[a]
    return v.decode() if isinstance(v, bytes) else v
for x, keep in [("a", 1 / 3), ("p", 0.0), ("q", 1 / 3)]:
    assert attr(f"{w}/{x}.h5", "contact") == "no_slip", x
    assert abs(attr(f"{w}/{x}.h5", "no_slip_keep") - keep) < 1e-15, x
got = {x: h5py.File(f"{w}/{x}_traj.h5", "r").attrs["travel"] for x in "apq"}
want = {"a": ns["deploy/agents/travel_u"][envs.index("ice"), 1],
        "p": ns["deploy/collectives/travel_u"][envs.index("gap"), t, 0, 1],
        "q": ns["deploy/collectives/travel_u"][envs.index("ice"), t, 0, 2]}
for x in "apq":
    assert got[x] == want[x], (x, got[x], want[x])
print("no_slip: recorded, differs from coulomb, exported episodes reproduce the stored travel")
PY
if out=$(mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" --from deploy --base "$W/ns.h5" --out "$W/from.h5" 2>&1); then
  fail "--from reused a no_slip base under coulomb"
fi
grep -q "run.contact (no_slip -> coulomb)" <<< "$out" || fail "--from did not name run.contact: $out"
echo "contact law: passed"
