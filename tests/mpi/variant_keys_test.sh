#!/usr/bin/env bash
# The study's variant keys on the tiny preset (2 ranks):
# - defaults change nothing: deploy.early_step > 0 only adds the *_early datasets, every other deploy
#   dataset equals a run without it bit for bit;
# - deploy.early_step = S records exactly the travel of an S-step deployment (the same episodes run for S steps);
# - deploy.uniform_agents = held_out and deploy.feature_placement = rear: the analysis stage re-simulates
#   deploy's episodes bit for bit (deploy_mismatches = 0), agents alone on flat (no features) travel as
#   under the default placement, and `divcoll export` of a held-out uniform pair and of an agent alone in an
#   environment with features gives scenes whose simulation reproduces the stored travel bit for bit;
# - connectors.damping > 0: the same re-simulation and export checks, the exported scene's connector springs
#   carrying the dashpot;
# - connectors.follower = true (damping 0): a uniform pair on flat travels as its agent alone;
# - analysis.familiarity_on = inputs: the run file gains only deploy/hidden/{type}/inputs (11 per state, beside
#   the same hidden states), and the familiarity fits embed those.
# Usage: variant_keys_test.sh DIVCOLL SOURCE_DIR
set -euo pipefail
D=$1 SRC=$2
source "$SRC/jobs/mpi-env.sh"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
fail() { echo "FAILED: $*"; exit 1; }
CFG=$SRC/configs/tiny.toml
BASE=('run.stages=["agents","connectors","deploy"]' 'connectors.kinds=["weak_uniform","weak_diverse"]')

mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" deploy.early_step=0 --out "$W/plain.h5" > /dev/null
mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" deploy.early_step=100 --out "$W/early.h5" > /dev/null
mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" deploy.episode_steps=100 --out "$W/short.h5" > /dev/null
/usr/bin/python3 - "$W" <<'EOF' || fail "deploy.early_step"
import sys, h5py, numpy as np
w = sys.argv[1]
plain, early, short = (h5py.File(f"{w}/{n}.h5", "r") for n in ["plain", "early", "short"])
# every dataset of the plain run is in the early run, bit for bit; the early run adds only the *_early ones
names = []
plain.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
for n in names:
    a, b = plain[n][()], early[n][()]
    assert a.shape == b.shape and a.tobytes() == b.tobytes(), n
extra = []
early.visititems(lambda n, o: extra.append(n) if isinstance(o, h5py.Dataset) and n not in names else None)
assert sorted(extra) == ["deploy/agents/travel_bl_early", "deploy/collectives/travel_bl_early"], extra
for g in ["agents", "collectives"]:
    e, s = early[f"deploy/{g}/travel_bl_early"][()], short[f"deploy/{g}/travel_bl"][()]
    ok = (early[f"deploy/{g}/status"][()] == 0) & (short[f"deploy/{g}/status"][()] == 0)
    assert ok.sum() > 0
    assert e[ok].tobytes() == s[ok].tobytes(), (g, np.max(np.abs(e[ok] - s[ok])))
print("early_step: the defaults unchanged; travel at step 100 = a 100-step deployment, bit for bit")
EOF

# held-out uniform pairs (population 6, batch 4 -> pairs 4 and 5) and the rear placement, with the analysis
V=(agents.population=6 connectors.batch_pairs=4 deploy.pairs=2 deploy.uniform_agents=held_out deploy.feature_placement=rear)
mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors","deploy","analysis"]' \
  'connectors.kinds=["weak_uniform","weak_diverse"]' "${V[@]}" --out "$W/held.h5" > /dev/null
mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors","deploy"]' \
  'connectors.kinds=["weak_uniform","weak_diverse"]' agents.population=6 connectors.batch_pairs=4 deploy.pairs=2 \
  --out "$W/held_default.h5" > /dev/null
h5dump -a /analysis/adversity/deploy_mismatches "$W/held.h5" | grep -q "(0): 0" || fail "the analysis stage does not reproduce deploy under held_out + rear"
"$D" export "$W/held.h5" --what pair --env step_up --type weak_uniform@uniform --replicate 0 --pair 1 --out "$W/p.h5" | tee "$W/p.log"
grep -q "agents 5 behind 5" "$W/p.log" || fail "held-out uniform pair 1 is not agent 5 with its clone"
"$D" export "$W/held.h5" --what alone --env step_up --agent 3 --out "$W/a.h5" > "$W/a.log"
for x in p a; do
  "$D" simulate --scene "$W/$x.h5" --steps 200 --out "$W/${x}_traj.h5" > /dev/null
done
/usr/bin/python3 - "$W" <<'EOF' || fail "export under the variant keys"
import sys, h5py, numpy as np
w = sys.argv[1]
f, g = h5py.File(f"{w}/held.h5", "r"), h5py.File(f"{w}/held_default.h5", "r")
envs = f["deploy"].attrs["environments"]
envs = (envs.decode() if isinstance(envs, bytes) else envs).split(",")
e = envs.index("step_up")
types = f["deploy"].attrs["types"]
t = (types.decode() if isinstance(types, bytes) else types).split(",").index("weak_uniform@uniform")
pair = h5py.File(f"{w}/p_traj.h5", "r").attrs["travel"]
alone = h5py.File(f"{w}/a_traj.h5", "r").attrs["travel"]
assert pair == f["deploy/collectives/travel_u"][e, t, 0, 1], (pair, f["deploy/collectives/travel_u"][e, t, 0, 1])
assert alone == f["deploy/agents/travel_u"][e, 3], (alone, f["deploy/agents/travel_u"][e, 3])
flat = envs.index("flat")
# no features on flat: the rear placement changes nothing there
assert f["deploy/agents/travel_u"][flat].tobytes() == g["deploy/agents/travel_u"][flat].tobytes()
print("held_out + rear: exported episodes reproduce the stored travel; flat unchanged")
EOF
# connectors.damping: the dashpots reach every scene the stages build and the exported scene files, so the
# analysis stage re-simulates deploy bit for bit and `divcoll export` + `divcoll simulate` reproduce a pair's travel
mpirun -np 2 "$D" run "$CFG" 'run.stages=["agents","connectors","deploy","analysis"]' \
  'connectors.kinds=["weak_uniform","weak_diverse"]' connectors.damping=10 --out "$W/damped.h5" > /dev/null
h5dump -a /analysis/adversity/deploy_mismatches "$W/damped.h5" | grep -q "(0): 0" || fail "the analysis stage does not reproduce deploy under connectors.damping"
"$D" export "$W/damped.h5" --what pair --env step_up --type weak_diverse@diverse --replicate 0 --pair 1 --out "$W/d.h5" > /dev/null
"$D" simulate --scene "$W/d.h5" --steps 200 --out "$W/d_traj.h5" > /dev/null
/usr/bin/python3 - "$W" <<'EOF2' || fail "connectors.damping"
import sys, h5py, numpy as np
w = sys.argv[1]
f, s = h5py.File(f"{w}/damped.h5", "r"), h5py.File(f"{w}/d.h5", "r")
c = s["connectors/spring_index"][()].ravel()
damp = s["springs/damping"][()]
assert np.all(damp[c] == 10.0) and np.count_nonzero(damp) == len(c), damp
envs = f["deploy"].attrs["environments"]
envs = (envs.decode() if isinstance(envs, bytes) else envs).split(",")
types = f["deploy"].attrs["types"]
t = (types.decode() if isinstance(types, bytes) else types).split(",").index("weak_diverse@diverse")
travel = h5py.File(f"{w}/d_traj.h5", "r").attrs["travel"]
stored = f["deploy/collectives/travel_u"][envs.index("step_up"), t, 0, 1]
assert travel == stored, (travel, stored)
print("damping: scene files carry the dashpots; exported episode reproduces the stored travel")
EOF2

# connectors.follower: connector springs without stiffness; with no dashpot a uniform pair on flat is an agent and
# its clone side by side, so it travels as the agent alone (up to rounding: the clone starts further ahead)
mpirun -np 2 "$D" run "$CFG" "${BASE[@]}" connectors.follower=true --out "$W/follower.h5" > /dev/null
/usr/bin/python3 - "$W" <<'EOF2' || fail "connectors.follower"
import sys, h5py, numpy as np
w = sys.argv[1]
f = h5py.File(f"{w}/follower.h5", "r")
envs = f["deploy"].attrs["environments"]
envs = (envs.decode() if isinstance(envs, bytes) else envs).split(",")
types = (f["deploy"].attrs["types"].decode() if isinstance(f["deploy"].attrs["types"], bytes) else f["deploy"].attrs["types"]).split(",")
e, t = envs.index("flat"), types.index("weak_uniform@uniform")
pair = f["deploy/collectives/travel_u"][e, t, 0, :]
alone = f["deploy/agents/travel_u"][e, :len(pair)]
assert np.all(f["deploy/collectives/status"][e, t, 0, :] == 0)
assert np.allclose(pair, alone, rtol=0, atol=1e-9), (pair, alone)
print("follower: uniform pairs on flat travel as their agent alone", pair, alone)
EOF2

# analysis.familiarity_on = inputs: deploy also stores the connectors' network inputs at the sampled (step, spring)
# (11 per state), every dataset of the default run is unchanged, and the familiarity fits embed the inputs
FULL=('run.stages=["agents","connectors","deploy","analysis"]' 'connectors.kinds=["weak_uniform","weak_diverse"]')
mpirun -np 2 "$D" run "$CFG" "${FULL[@]}" --out "$W/fam_hidden.h5" > /dev/null
mpirun -np 2 "$D" run "$CFG" "${FULL[@]}" analysis.familiarity_on=inputs --out "$W/fam_inputs.h5" > /dev/null
"$D" schema --check "$W/fam_inputs.h5" > /dev/null || fail "the inputs run file does not match the run-file schema"
/usr/bin/python3 - "$W" <<'EOF2' || fail "analysis.familiarity_on"
import sys, h5py, numpy as np
w = sys.argv[1]
h, i = h5py.File(f"{w}/fam_hidden.h5", "r"), h5py.File(f"{w}/fam_inputs.h5", "r")
names = []
h.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
extra = []
i.visititems(lambda n, o: extra.append(n) if isinstance(o, h5py.Dataset) and n not in names else None)
assert sorted(extra) == ["deploy/hidden/weak_diverse@diverse/inputs", "deploy/hidden/weak_uniform@uniform/inputs"], extra
for n in names:
    if n.startswith("analysis/familiarity") or n.startswith("analysis/timing"):
        continue
    a, b = h[n][()], i[n][()]
    assert a.shape == b.shape and a.tobytes() == b.tobytes(), n
for t in ["weak_uniform@uniform", "weak_diverse@diverse"]:
    x = i[f"deploy/hidden/{t}/inputs"][()]
    st = i[f"deploy/hidden/{t}/states"][()]
    assert x.shape == st.shape[:4] + (11,), (x.shape, st.shape)   # the controller's 11 inputs per state
    ok = np.isfinite(x).all(axis=-1)
    assert ok.sum() > 0 and (ok == np.isfinite(st).all(axis=-1)).all()
    v = x[ok]
    assert set(np.unique(v[:, 8:10])) <= {0.0, 1.0}          # touch flags
    assert np.all((v[:, 10] > 0.2) & (v[:, 10] < 3))          # l / L
    # the fits embedded input vectors: as many states as the hidden run's fits (same samples), other coordinates
    nh, ni = h[f"analysis/familiarity/{t}/n_states"][()], i[f"analysis/familiarity/{t}/n_states"][()]
    assert nh.tobytes() == ni.tobytes() and ni.sum() > 0, (nh, ni)
    c = i[f"analysis/familiarity/{t}/counts"][()]
    assert np.all(c[..., :3].sum(axis=-1) == ni.sum(axis=-1)), (c, ni)
    eh, ei = h[f"analysis/familiarity/{t}/embedding"][()], i[f"analysis/familiarity/{t}/embedding"][()]
    assert eh.tobytes() != ei.tobytes()
print("familiarity_on = inputs: 11 inputs per sampled state beside the unchanged hidden states; the fits embed them")
EOF2

echo "variant keys: passed"
