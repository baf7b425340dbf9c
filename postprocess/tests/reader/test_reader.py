"""The labelled reader (divcoll_post.open) on a real run file: every dataset opens with the dimension names
and labels its own attributes give, selections by name equal h5py's positional reads, examples/
fig2a_numbers.py gives exactly the numbers fig2.py computes, and `pip install --no-build-isolation
--no-index ./postprocess` installs the package offline into a venv that sees Debian's packages.

Needs the divcoll binary (DIVCOLL_BINARY, set by ctest) for the run file: the tiny preset's agents,
connectors and deploy stages (a few seconds). Its own ctest entry (postprocess.reader), outside
postprocess/tests' discovery, so that the pip install runs beside the figure tests."""

import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
POST = os.path.join(HERE, "..", "..")
SOURCE = os.path.join(POST, "..")
sys.path.insert(0, POST)

import divcoll_post  # noqa: E402
from divcoll_post.figures import fig2  # noqa: E402
from divcoll_post import results as R  # noqa: E402

BIN = os.environ.get("DIVCOLL_BINARY", os.path.join(SOURCE, "build", "divcoll"))

try:
    import xarray  # noqa: F401

    HAVE_XARRAY = True
except ImportError:  # pragma: no cover - depends on the machine
    HAVE_XARRAY = False

_RUN = {}


def tiny_run():
    """Path of a tiny run file with the agents, connectors and deploy stages (made once)."""
    if "path" not in _RUN:
        d = tempfile.mkdtemp(prefix="divcoll_reader_test_")
        _RUN["dir"] = d
        path = os.path.join(d, "tiny.h5")
        env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        r = subprocess.run([BIN, "run", os.path.join(SOURCE, "configs", "tiny.toml"),
                            "run.stages=agents,connectors,deploy", "--out", path],
                           capture_output=True, text=True, env=env, timeout=600)
        if r.returncode != 0:
            raise RuntimeError(f"divcoll run failed ({r.returncode}):\n{r.stdout}\n{r.stderr}")
        _RUN["path"] = path
    return _RUN["path"]


def tearDownModule():
    if "dir" in _RUN:
        shutil.rmtree(_RUN["dir"], ignore_errors=True)


def load_example():
    spec = importlib.util.spec_from_file_location("fig2a_numbers", os.path.join(POST, "examples", "fig2a_numbers.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@unittest.skipUnless(os.path.exists(BIN), f"no divcoll binary at {BIN} (set DIVCOLL_BINARY)")
@unittest.skipUnless(HAVE_XARRAY, "xarray missing (Debian's python3-xarray; jobs/install-deps.sh installs it)")
class Reader(unittest.TestCase):
    def test_every_dataset_is_labelled_from_its_own_attributes(self):
        path = tiny_run()
        with divcoll_post.open(path) as run, h5py.File(path, "r") as f:
            names = run.datasets()
            self.assertGreater(len(names), 20)
            for name in names:
                a = run[name]
                d = f[name]
                self.assertEqual(a.shape, d.shape, name)
                self.assertEqual(len(a.dims), d.ndim, name)
                self.assertEqual(",".join(a.dims), d.attrs["axes"], name)
                self.assertTrue(a.attrs["unit"] and a.attrs["doc"], name)
                for dim in a.dims:  # a labelled axis has one label per entry
                    if dim in a.coords:
                        self.assertEqual(a.coords[dim].size, a.sizes[dim], name)
                np.testing.assert_array_equal(a.values, d[()], err_msg=name)

    def test_selection_by_name_is_hdf5s_positional_read(self):
        path = tiny_run()
        with divcoll_post.open(path) as run, h5py.File(path, "r") as f:
            t = run.deploy.collectives.travel_bl
            self.assertEqual(t.dims, ("env", "type", "replicate", "pair"))
            self.assertEqual(t.attrs["unit"], "BL")
            envs = f["deploy"].attrs["environments"].split(",")
            types = f["deploy"].attrs["types"].split(",")
            self.assertEqual(list(t.env.values), envs)
            self.assertEqual(list(t.type.values), types)
            sel = t.sel(env="ice", type="weak_diverse@diverse")
            self.assertEqual(sel.dims, ("replicate", "pair"))
            raw = f["deploy/collectives/travel_bl"][envs.index("ice"), types.index("weak_diverse@diverse")]
            np.testing.assert_array_equal(sel.values, raw)
            # fixed labels and a subgroup reached by path
            pairs = run["deploy/diverse_pairs"]
            self.assertEqual(list(pairs.slot.values), ["posterior", "anterior"])
            states = run["deploy/hidden/weak_diverse@diverse/states"]
            self.assertEqual(states.dims, ("env", "replicate", "pair", "sample", "neuron"))
            self.assertEqual(run.agents.final.rest_pos.dims, ("agent", "mass", "xy"))
            self.assertIn("travel_bl", repr(run.deploy.agents))
            with self.assertRaises(AttributeError):
                run.deploy.nothing_here

    def test_a_file_without_the_schemas_attributes_is_named(self):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "old.h5")
            with h5py.File(p, "w") as f:
                f.attrs["format"] = "divcoll-run"
                f["deploy/agents/travel_bl"] = np.zeros((2, 3))
            with divcoll_post.open(p) as run:
                with self.assertRaisesRegex(divcoll_post.RunFileError, "no 'axes' attribute"):
                    run.deploy.agents.travel_bl
            with h5py.File(p, "a") as f:
                f.attrs["format"] = "divcoll-scene"
            with self.assertRaisesRegex(divcoll_post.RunFileError, "not a divcoll run file"):
                divcoll_post.open(p)

    def test_example_gives_fig2s_numbers(self):
        path = tiny_run()
        mine = load_example().numbers(path)
        theirs = fig2.compute(R.load_deploy(path))
        self.assertEqual(len(mine), sum(len(theirs[s]) for s in ("flat", "novel")))
        for (setting, who), (m, lo, hi, n_ok, bad) in mine.items():
            st = theirs[setting][who]
            self.assertEqual((m, lo, hi, n_ok, bad), (st.mean, st.lo, st.hi, st.n_ok, st.n_bad), (setting, who))
            self.assertTrue(np.isfinite(m), (setting, who))


@unittest.skipUnless(os.path.exists(BIN), f"no divcoll binary at {BIN} (set DIVCOLL_BINARY)")
@unittest.skipUnless(HAVE_XARRAY, "xarray missing (Debian's python3-xarray; jobs/install-deps.sh installs it)")
class StageList(unittest.TestCase):
    def test_the_stages_are_the_pipelines_list_in_run_order(self):
        """reader.STAGES is read from src/config/pipeline.hpp: the same names, in the same order, as the run.stages
        default that the program writes into configs/paper.toml"""
        import tomllib
        from divcoll_post import reader
        with open(os.path.join(POST, "..", "configs", "paper.toml"), "rb") as f:
            self.assertEqual(reader.STAGES, tomllib.load(f)["run"]["stages"])

    def test_a_missing_stage_list_is_named(self):
        from divcoll_post import reader
        with tempfile.TemporaryDirectory() as d:
            with self.assertRaisesRegex(RuntimeError, "cannot read the pipeline's stage list"):
                reader.pipeline_stages(os.path.join(d, "pipeline.hpp"))
            path = os.path.join(d, "other.hpp")
            with open(path, "w") as f:
                f.write("#pragma once\n")
            with self.assertRaisesRegex(RuntimeError, "no stage list"):
                reader.pipeline_stages(path)


class OfflineInstall(unittest.TestCase):
    def test_pip_install_without_an_index(self):
        """The README's command, on a copy of the package (the build writes into the source folder)."""
        path = tiny_run()
        with tempfile.TemporaryDirectory() as d:
            shutil.copytree(POST, os.path.join(d, "postprocess"),
                            ignore=shutil.ignore_patterns("tests", "gallery", "__pycache__", "*.png", "*.pdf"))
            venv = os.path.join(d, "venv")
            subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", venv], check=True, timeout=300)
            py = os.path.join(venv, "bin", "python")
            env = dict(os.environ, PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
            env.pop("PYTHONPATH", None)
            r = subprocess.run([py, "-m", "pip", "install", "--no-build-isolation", "--no-index", "./postprocess"],
                               cwd=d, capture_output=True, text=True, env=env, timeout=600)
            self.assertEqual(r.returncode, 0, r.stdout + r.stderr)
            # the installed package, from elsewhere, reads the run file by name
            code = ("import divcoll_post, sys; run = divcoll_post.open(sys.argv[1]); "
                    "t = run.deploy.collectives.travel_bl.sel(env='flat', type='weak_diverse@diverse'); "
                    "print(divcoll_post.__file__); print(t.dims)")
            r = subprocess.run([py, "-c", code, path], cwd=venv, capture_output=True, text=True, env=env, timeout=300)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn(os.path.join(venv, "lib"), r.stdout)
            self.assertIn("('replicate', 'pair')", r.stdout)
            # and the example runs with it
            r = subprocess.run([py, os.path.join(d, "postprocess", "examples", "fig2a_numbers.py"), path],
                               cwd=venv, capture_output=True, text=True, env=env, timeout=300)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("weak_diverse@diverse", r.stdout)


if __name__ == "__main__":
    unittest.main()
