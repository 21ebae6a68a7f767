"""One process of the two-process test (tests/studies/test_multihost.py): the ensemble and the
Q-learning sweep, written to a pickle by process 0. Run as
``python multihost_worker.py OUT [PORT PROCESS_ID]``; with a port it joins a 2-process
``jax.distributed`` run on 127.0.0.1 (CPU collectives over gloo), without one it runs alone."""

import os
import pickle
import sys

os.environ["XLA_FLAGS"] = "--xla_force_host_platform_device_count=2"

import jax

out = sys.argv[1]
if len(sys.argv) > 2:
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(
        coordinator_address=f"127.0.0.1:{sys.argv[2]}",
        num_processes=2,
        process_id=int(sys.argv[3]),
        local_device_ids=[0, 1],
    )

from jswim import env  # noqa: E402
from jswim.agents.qlearning import QConfig  # noqa: E402
from jswim.studies import ensemble, qlearn  # noqa: E402

policy, start = ensemble.signature_policy(env.make_params("purcell"))
stats = ensemble.run(
    policy, env.make_params("purcell", init=start), n=4096, zetas=(0.5, 1.0), steps=40, every=10
)
sweep = qlearn.study(QConfig(steps=200), swimmers=("purcell",), zetas=(0.0, 1.0), n_seeds=64)
if jax.process_index() == 0:
    with open(out, "wb") as f:
        pickle.dump(
            {
                "devices": jax.device_count(),
                "processes": jax.process_count(),
                "ensemble": [s._asdict() for s in stats],
                "qlearn": [s._asdict() for s in sweep],
            },
            f,
        )
