"""Sharded bake on a local Dask cluster against one process: 20 000 Cornell-box probes at 2 %
(docs/design/sharding.md). Run with the package installed (a release wheel: `pip install
crates/gcr-py`) and the probes made by `python3 xtask/py/area_probes.py cornell-box 20000 /tmp/P20k.txt`."""
import os, time, statistics, numpy as np
import gcr, gcr.distributed
rows = np.loadtxt("/tmp/P20k.txt"); P, N = rows[:, :3], rows[:, 3:]
opts = dict(target_error=0.02, block_points=1000)
def single():
    return gcr.solve(gcr.Scene.load("cornell-box"), **opts).radiosity(P, N)
if __name__ == "__main__":
    ref = single()
    t1 = []
    for _ in range(5):
        t = time.perf_counter(); single(); t1.append(time.perf_counter() - t)
    if os.environ.get("WORKER_THREADS"):  # rayon's threads in each worker; default every core
        os.environ["RAYON_NUM_THREADS"] = os.environ["WORKER_THREADS"]
    from dask.distributed import Client, LocalCluster
    t = time.perf_counter()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster); start = time.perf_counter() - t
    for shards in (2, 8):
        ts = []
        for k in range(6):
            gcr.distributed._solution.cache_clear()
            client.run(gcr.distributed._solution.cache_clear)  # each run loads and solves anew
            t = time.perf_counter()
            v, e = gcr.distributed.shard_values(client, "cornell-box", P, N, shards=shards, block_points=1000, solve={"target_error": 0.02})
            ts.append(time.perf_counter() - t)
            assert v.tobytes() == ref[0].tobytes() and e.tobytes() == ref[1].tobytes()
        ts = ts[1:]
        print(f"shards {shards}: median {statistics.median(ts):.3f} s (min {min(ts):.3f}, max {max(ts):.3f}); "
              f"single process median {statistics.median(t1):.3f} s; ratio {statistics.median(ts)/statistics.median(t1):.3f}; identical")
    print(f"cluster start {start:.2f} s")
    client.close(); cluster.close()
