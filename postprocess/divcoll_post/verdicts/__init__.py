"""The pre-registered protocol (configs/studies/verdicts_protocol.md) as code: the arrays each run keeps, every
claim's effect, the hierarchical bootstrap, Holm's procedure and the four verdicts.

- `arrays.py`: a run's arrays (`extract(run.h5)`, kept as `<run>.arrays.json` beside its summary) hold per connector
  and environment what the claims read, so a study folder kept without its run files still gives every number.
- `population.py`: `Population` turns one run's arrays (and, for the supplement stages, the arrays of the run that
  computed them for the same seed) into batched views for connector draws; `load_study` reads a study folder's.
- `effects.py`: each claim's effect over a population (`e_*`); `describe.py`: the numbers behind it for one run (`d_*`).
- `claims.py`: `CLAIMS`, the registry, one `Claim` entry a claim.
- `estimator.py`: the bootstrap, Holm's procedure and `judge`, which evaluates a family of claims over populations.

Everything is re-exported here (`from divcoll_post import verdicts as V; V.CLAIMS, V.judge, ...`).
`python3 -m divcoll_post.verdicts STUDY_DIR ...` runs the verdict page's command line (divcoll_post.verdict_page).
"""

from .arrays import ARRAYS_FORMAT, ARRAYS_VERSION, arrays_path, extract, read_arrays, write_arrays  # noqa: F401
from .claims import (BL, BY_ID, CLAIMS, DROP, ENV, EPISODE_TYPES, NOT_EXPORTED_DTW, N_AGENTS, N_ANALYSIS,  # noqa: F401
                     N_DEPLOY, N_GRADED, N_NOVEL, N_SCALING, N_SPECIALISTS, N_TRAINED, N_UNTRAINED, SHARE, U, Claim,
                     Episodes, holds, region)
from .describe import (d_all_drop, d_alone_drop, d_beat_alone, d_beat_alone_1000, d_best_flat,  # noqa: F401
                       d_best_novel, d_disrupted, d_fitness, d_graded, d_greatest_drop, d_least_drop, d_most_envs,
                       d_random, d_scaling, d_specialists, d_strong, d_transplant, d_untrained, d_vs_alone_novel,
                       d_wind, d_wind_calibrated, d_worse_better, f3, g3)
from .effects import (MATCHED, SEVERE, STRONG_TYPES, WD, WEAK_TYPES, WU, e_all_drop,  # noqa: F401
                      e_alone_greatest_drop, e_alone_severe, e_beat_alone, e_beat_alone_1000, e_better_comparable,
                      e_disrupted_more, e_fitness, e_generalist_beats_specialist, e_graded, e_more_familiar, e_random,
                      e_scaling_better, e_scaling_grows, e_strong_poor, e_transplant_interaction,
                      e_transplant_small_loss, e_uniform_more_novel_only, e_uniform_more_train_only,
                      e_untrained_severe, e_wdd_best_flat, e_wdd_best_novel, e_wdd_least_drop, e_wdd_most_envs,
                      e_wdd_vs_alone_novel, e_wind_exclusive_ratio, e_wind_unfamiliar, e_wind_unfamiliar_calibrated,
                      e_worse_altered_more, e_worse_changed_more)
from .estimator import (ALPHA, BOOT_SEED, B_DEFAULT, Result, bootstrap, holm, hypotheses, interval,  # noqa: F401
                        judge, power_at_edge)
from .population import Population, load_study, population_from_summary  # noqa: F401
