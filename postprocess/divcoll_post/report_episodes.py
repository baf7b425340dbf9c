"""The episodes behind the report's numbers: for every cell a number averages over (an environment and an agent
alone, a collective type, a specialist or a chain), the `divcoll export` command of the cell's median ok episode
and the `divcoll simulate` command that turns that scene back into the episode (travel equal to the run file's
bit for bit). Used by report.py (`Episodes(run, run_arg)`): the claims table's "episodes" column, Fig. 2A per
environment, the single episodes of the movie and contact sheet captions, and the list "Episodes behind the
numbers" that all those links lead to (Markdown; report_html.py gives each list item its anchor).

Median ok episode: among the cell's episodes with status ok and a finite travel, the one at rank (n - 1) // 2 of
the sorted travels; collectives, specialists and chains from replicate 0 (the first connector), agents alone from
the whole population.
"""
import re
import shlex

import numpy as np

from .reader import complete, list_attr  # noqa: E402
from .reader import open as open_labelled  # noqa: E402
from .results import ok_mean  # noqa: E402


def _median_ok(travel, status):
    """index of the median ok episode of a 1-D cell, or None"""
    ok = (status == 0) & np.isfinite(travel)
    if not ok.any():
        return None
    idx = np.flatnonzero(ok)
    return int(idx[np.argsort(travel[ok], kind="stable")[(len(idx) - 1) // 2]])


class Episodes:
    """the export commands of a run file's episodes, registered as the report asks for them (anchor → line)"""

    def __init__(self, run, run_arg):
        self.run_arg = shlex.quote(run_arg)
        self.items = {}  # anchor -> Markdown text of the list item, in the order asked for
        self.envs, self.types, self.spec_envs, self.scale_envs, self.sizes = [], [], [], [], []
        with open_labelled(run) as f:
            cfg = f.config() or {}
            self.steps = {"deploy": cfg.get("deploy", {}).get("episode_steps"),
                          "scaling": cfg.get("scaling", {}).get("episode_steps")}

            def arrays(g):
                return g.travel_bl, g.status

            if "deploy/collectives/travel_bl" in f and "deploy/agents/travel_bl" in f:
                d = f.deploy
                self.envs, self.types = list_attr(d, "environments"), list_attr(d, "types")
                self.alone_t, self.alone_s = arrays(d.agents)
                self.coll_t, self.coll_s = arrays(d.collectives)
                self.envs = self.envs[: min(len(self.envs), self.coll_t.sizes["env"])]
            if "specialists/travel_bl" in f and complete(f, "specialists"):
                self.spec_envs = list_attr(f.specialists, "environments")
                self.spec_t, self.spec_s = arrays(f.specialists)
            if "scaling/travel_bl" in f and complete(f, "scaling"):
                self.scale_envs = list_attr(f.scaling, "environments")
                self.sizes = [int(n) for n in f.scaling.sizes.values]
                self.chain_t, self.chain_s = arrays(f.scaling)

    def _add(self, anchor, what, args, out, stage):
        if anchor not in self.items:
            cmd = f"divcoll export {self.run_arg} {args} --out {out}"
            sim = f"divcoll simulate --scene {out} --steps {self.steps[stage]} --out {out[:-3]}_traj.h5"
            self.items[anchor] = f"{what}: `{cmd}`, then `{sim}`"
        return anchor

    # one method per kind of episode; each returns the anchor of the list item, or None (no ok episode)
    def alone(self, env):
        if env not in self.envs:
            return None
        v, s = self.alone_t.sel(env=env).values, self.alone_s.sel(env=env).values
        i = _median_ok(v, s)
        if i is None:
            return None
        n = int(((s == 0) & np.isfinite(v)).sum())
        return self._add(f"ep-{env}-alone", f"agent {i} alone in {env}, {v[i]:.3f} BL (median of {n} ok)",
                         f"--what alone --env {env} --agent {i}", f"{env}_agent{i}.h5", "deploy")

    def pair(self, env, typ, pair=None, replicate=0):
        """the median ok pair of replicate 0 of a cell, or a given pair"""
        if env not in self.envs or typ not in self.types:
            return None
        cell = dict(env=env, type=typ, replicate=replicate)
        v, s = self.coll_t.sel(cell).values, self.coll_s.sel(cell).values
        fixed = pair is not None
        if not fixed:
            pair = _median_ok(v, s)
            if pair is None:
                return None
        tag = typ.replace("@", "-at-")
        anchor = f"ep-{env}-{tag}" + (f"-r{replicate}-p{pair}" if fixed else "")
        how = "" if fixed else f" (median of replicate {replicate}'s {int(((s == 0) & np.isfinite(v)).sum())} ok)"
        return self._add(anchor, f"{typ} replicate {replicate} pair {pair} in {env}, {v[pair]:.3f} BL{how}",
                         f"--what pair --env {env} --type {typ} --replicate {replicate} --pair {pair}",
                         f"{env}_{typ.replace('@', '_at_')}_r{replicate}_p{pair}.h5", "deploy")

    def specialist(self, env):
        if env not in self.spec_envs:
            return None
        v, s = (a.sel(env=env, replicate=0).values for a in (self.spec_t, self.spec_s))
        q = _median_ok(v, s)
        if q is None:
            return None
        return self._add(f"ep-spec-{env}", f"the {env} specialist 0, pair {q}, {v[q]:.3f} BL (median ok)",
                         f"--what specialist --env {env} --replicate 0 --pair {q}", f"spec_{env}_r0_p{q}.h5", "deploy")

    def chain(self, env, size, variant):
        if env not in self.scale_envs or size not in self.sizes:
            return None
        cell = dict(env=env, size=size, variant=variant, replicate=0)
        v, s = self.chain_t.sel(cell).values, self.chain_s.sel(cell).values
        q = _median_ok(v, s)
        if q is None:
            return None
        return self._add(f"ep-chain-{env}-n{size}-{variant}",
                         f"a {variant} chain of {size}, replicate 0, draw {q}, in {env}, {v[q]:.3f} BL (median ok)",
                         f"--what chain --env {env} --size {size} --variant {variant} --replicate 0 --draw {q}",
                         f"chain_{env}_n{size}_{variant}_r0_d{q}.h5", "scaling")

    # what the report shows
    def fig2a_table(self):
        """Fig. 2A per environment (Markdown): mean BL over a cell's ok episodes, linked to its median episode"""
        if not self.envs:
            return []
        out = ["## Fig. 2A per environment: numbers and their episodes", "",
               "Mean travel (BL) over the ok episodes of each cell; each number links to the `divcoll export` command "
               "of the cell's median ok episode (replicate 0 for collectives), whose scene `divcoll simulate` turns "
               "back into that episode's travel bit for bit.", "",
               "| environment | agents alone | " + " | ".join(f"`{t}`" for t in self.types) + " |",
               "|---" * (len(self.types) + 2) + "|"]
        for env in self.envs:
            cells = []
            a = self.alone(env)
            m = ok_mean(self.alone_t.sel(env=env), self.alone_s.sel(env=env))[0]
            cells.append(f"[{m:.3f}](#{a})" if a else "—")
            for typ in self.types:
                m = ok_mean(self.coll_t.sel(env=env, type=typ), self.coll_s.sel(env=env, type=typ))[0]
                c = self.pair(env, typ)
                cells.append(f"[{m:.3f}](#{c})" if c else ("—" if not np.isfinite(m) else f"{m:.3f}"))
            out.append(f"| {env} | " + " | ".join(cells) + " |")
        return out + [""]

    def links(self, label, anchors):
        """'label: [env](#a) · [env](#b)' over the anchors that exist ('' if none)"""
        got = [f"[{env.replace('_', ' ')}](#{a})" for env, a in anchors if a]
        return f"{label}: " + " · ".join(got) if got else ""

    def claim_cell(self, claim, number):
        """the claims table's episodes cell of a registry claim (verdicts.Claim: its `episodes`, a verdicts.Episodes)
        whose number text is `number` (Markdown)"""
        ep = claim.episodes
        note, alone, types, where = ep.note, ep.alone, ep.types, ep.envs
        novel = [e for e in self.envs if e != "flat"]
        scope = {"flat": ["flat"], "novel": novel, "all": self.envs, "wind": ["flat", "wind"], "none": [],
                 "specialists": self.spec_envs, "chains": []}
        select = {
            "named": [t for t in self.types if re.search(rf"(?<![\w@]){re.escape(t)}(?![\w@])", number)],
            "matched": [t for t in self.types if t.split("@")[0].endswith("_" + t.split("@")[1])],
            "weak": [t for t in self.types if t.startswith("weak")],
            "all": self.types,
            "pair": [t for t in ("weak_uniform@uniform", "weak_diverse@diverse") if t in self.types],
        }
        types = select[types] if isinstance(types, str) else [t for t in types if t in self.types]
        envs = scope[where]
        parts = []
        if where == "specialists":
            parts.append(self.links("specialist", [(e, self.specialist(e)) for e in self.spec_envs]))
        if where == "chains":
            for n in self.sizes:
                for v in ("uniform", "diverse"):
                    parts.append(self.links(f"{v} chains of {n}", [(e, self.chain(e, n, v)) for e in self.scale_envs
                                                                   if e != "flat"]))
        if alone:
            parts.append(self.links("agents alone", [(e, self.alone(e)) for e in envs]))
        for t in types:
            parts.append(self.links(f"`{t}`", [(e, self.pair(e, t)) for e in envs]))
        cell = " ; ".join(p for p in parts if p)
        return (note + " " + cell).strip() or "—"

    def listing(self):
        """the list every link leads to (Markdown; each item starts with its anchor)"""
        if not self.items:
            return []
        return ["## Episodes behind the numbers", "",
                "Each episode a number of this page links to: `divcoll export` writes its scene file and prints the "
                "travel the run file records for it; `divcoll simulate` on that scene reproduces the episode (travel "
                "bit for bit; `PYTHONPATH=postprocess /usr/bin/python3 -m divcoll_post.movie --episode SCENE TRAJ "
                "--out X.mp4`, from the checkout's root, renders it). `divcoll` is `build/divcoll` of the checkout; "
                "both write their files into the current folder.", ""] + \
            [f'- <a id="{a}"></a>{t}' for a, t in self.items.items()] + [""]
