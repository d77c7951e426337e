"""Running a Rust peer bench from a peer script, for paired rounds: each round runs the Rust bench (which
rewrites its inputs and timings into its peer folder) right before the script times the peer, so that every
skytie / peer ratio compares two measurements taken seconds apart on this shared, noisy machine."""
import os
import subprocess


def run_rust_bench(bench, folder):
    """`cargo bench -p skytie-stages --bench BENCH` from this repository, writing into `folder`
    (= $SKYTIE_PEER_DIR/<name>, so SKYTIE_PEER_DIR is set to its parent)."""
    repo = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, SKYTIE_PEER_DIR=os.path.dirname(os.path.abspath(folder)))
    subprocess.run(["cargo", "bench", "-q", "-p", "skytie-stages", "--bench", bench], cwd=repo, env=env,
                   check=True, stdout=subprocess.DEVNULL)
