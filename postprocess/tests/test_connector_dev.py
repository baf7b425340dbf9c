"""The development page of connector training (divcoll_post.connector_dev): A5's selection rule, the cost count and
the page on a synthetic kept study."""
import json
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from divcoll_post import connector_dev as D  # noqa: E402

REFS = ["free@uniform", "free@diverse", "passive@uniform", "passive@diverse", "follower@uniform", "follower@diverse"]


def run_arrays(seed, wu, wd, alone=10.0):
    """a development run's arrays: flat only, weak uniform and weak diverse as trained at wu and wd BL"""
    types = ["weak_uniform@uniform", "weak_uniform@diverse", "weak_diverse@uniform", "weak_diverse@diverse"]
    coll = [[[wu], [wu], [wd], [wd]]]
    return {"format": "divcoll-verdict-arrays", "version": 1, "seed": seed, "git_commit": "synthetic",
            "connectors": {"untrained_bl": {}, "curves": {"weak_uniform": {"train_bl": [[1.0], [2.0], [wu / 3]]},
                                                          "weak_diverse": {"train_bl": [[1.0], [2.0], [wd / 3]]}},
                           "wall_s": 100.0},
            "deploy": {"environments": ["flat"], "types": types, "alone_bl": [alone], "collectives_bl": coll,
                       "collectives_ok": [[[100]] * 4], "references": REFS,
                       "references_bl": [[alone, alone, 3.0, 2.5, 6.0, 5.0]]}}


def summary(cfg):
    return {"format": "divcoll-run-summary", "git_commit": "synthetic", "config": {"connectors": cfg}}


def kept(d, variants, added=None):
    """variants: [(name, set, {seed: (wu, wd)}, connectors config)]; added: {name: date} of late variants"""
    runs = []
    with open(os.path.join(d, "study.toml"), "w") as fh:
        fh.write('format = "divcoll-study"\nname = "dev"\n')
        for name, keys, by_seed, cfg in variants:
            fh.write(f'[[variant]]\nname = "{name}"\nset = {json.dumps(keys)}\n'
                     + (f'added = "{added[name]}"\n' if added and name in added else ""))
            os.makedirs(os.path.join(d, name), exist_ok=True)
            for seed, (wu, wd) in by_seed.items():
                with open(os.path.join(d, name, f"seed{seed}.arrays.json"), "w") as a:
                    json.dump(run_arrays(seed, wu, wd), a)
                with open(os.path.join(d, name, f"seed{seed}.summary.json"), "w") as s:
                    json.dump(summary(cfg), s)
                runs.append((name, seed))
        for name, seed in runs:
            fh.write(f'[[run]]\nvariant = "{name}"\nseed = {seed}\npath = "{name}/seed{seed}.h5"\nstatus = "complete"\n')


PLAIN = {"iterations": 100, "batch_pairs": 100, "grad_samples": 1, "optimizer": "adam", "keep_best": False}
KEEP = dict(PLAIN, keep_best=True, validation_pairs=32)


class Selection(unittest.TestCase):
    def test_the_cost_counts_gradient_candidate_and_validation_episodes(self):
        self.assertEqual(D.pair_episodes({"connectors": PLAIN}), 10000)
        self.assertEqual(D.pair_episodes({"connectors": KEEP}), 10000 + 101 * 32)
        self.assertEqual(D.pair_episodes({"connectors": dict(PLAIN, optimizer="es", es_popsize=8)}), 80000)

    def test_the_largest_share_wins_a_tie_goes_to_the_cheaper_and_readings_never_win(self):
        with tempfile.TemporaryDirectory() as d:
            kept(d, [("paper", [], {101: (5.0, 4.0), 102: (5.0, 4.0)}, PLAIN),
                     ("better", ["connectors.keep_best=true"], {101: (5.1, 4.1), 102: (5.1, 4.1)}, KEEP),
                     ("stiff", ["connectors.weak_stiffness=1000"], {101: (9.0, 9.0), 102: (9.0, 9.0)}, PLAIN),
                     ("half", ["connectors.lr=0.01"], {101: (9.5, 9.5)}, PLAIN)])
            c = {x.name: x for x in D.candidates(d)}
            self.assertAlmostEqual(c["paper"].S, 0.45)
            self.assertAlmostEqual(c["paper"].S_follower, (0.5 / 0.6 + 0.4 / 0.5) / 2)
            self.assertFalse(c["stiff"].eligible)
            # better is within 0.02 of paper's S: the tie goes to paper, the cheaper; half lacks population 102
            self.assertEqual(D.select(list(c.values()), [101, 102]).name, "paper")
            with open(D.write(d, os.path.join(d, "page"))) as fh:
                page = fh.read()
        self.assertIn("**paper**", page)
        self.assertIn("| stiff | reading |", page)

    def test_a_candidate_added_after_the_choice_is_reported_and_never_chosen(self):
        with tempfile.TemporaryDirectory() as d:
            kept(d, [("paper", [], {101: (5.0, 4.0), 102: (5.0, 4.0)}, PLAIN),
                     ("late", ["connectors.lr=0.01"], {101: (9.5, 9.5), 102: (9.5, 9.5)}, PLAIN)],
                 added={"late": "2026-12-06"})
            c = {x.name: x for x in D.candidates(d)}
            self.assertFalse(c["late"].eligible)
            self.assertEqual(D.select(list(c.values()), [101, 102]).name, "paper")
            with open(D.write(d, os.path.join(d, "page"))) as fh:
                page = fh.read()
        self.assertIn("| late | added 2026-12-06, reported only |", page)


def budget_page(dev_runs, budget_runs):
    """the budget page of a kept study whose paper_1000 runs have `budget_runs` beside a development study whose
    paper runs have `dev_runs` ({seed: (weak uniform, weak diverse) BL})"""
    with tempfile.TemporaryDirectory() as d:
        dev, budget = os.path.join(d, "dev"), os.path.join(d, "budget")
        os.makedirs(dev)
        os.makedirs(budget)
        kept(dev, [("paper", [], dev_runs, PLAIN)])
        kept(budget, [("paper_1000", ["connectors.iterations=1000"], budget_runs, dict(PLAIN, iterations=1000))])
        with open(D.write_budget(budget, os.path.join(d, "page"), compare=dev)) as fh:
            return fh.read()


class Budget(unittest.TestCase):
    def test_the_budget_page_sets_each_training_beside_its_run_at_the_papers_budget(self):
        page = budget_page({101: (5.0, 4.0), 102: (5.0, 4.0)}, {101: (6.5, 5.5), 102: (6.5, 5.5)})
        # S: (0.65 + 0.55) / 2 against (0.5 + 0.4) / 2; 1000 iterations × 100 pairs
        self.assertIn("| paper_1000 | 0.600 |", page)
        self.assertIn("| 100,000 |", page)
        self.assertIn("| paper → paper_1000 | 0.450 | 0.600 | +0.150 |", page)

    def test_the_comparison_uses_only_the_populations_the_budget_study_has(self):
        page = budget_page({101: (5.0, 4.0), 102: (1.0, 1.0)}, {101: (6.5, 5.5)})
        self.assertIn("| paper → paper_1000 | 0.450 | 0.600 | +0.150 |", page)
        # the synthetic curves hold 3 iterations (1, 2, travel / 3): iteration 0 is 1.0, later marks are not there
        self.assertIn("| paper_1000 | weak_uniform | 1.00 | — |", page)


if __name__ == "__main__":
    unittest.main()
