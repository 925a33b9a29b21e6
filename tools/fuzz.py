"""Differential MJCF fuzzer: our parse + compile against MuJoCo's parser on mutated models.

Usage: `python -m tools.fuzz N [--seed S] [--show K] [--timeout SECONDS]`

Builds N documents (mutations of the seed models in `tools.mjcf_differential`, and
generated ones), compiles each with `mujoco.MjModel.from_xml_path` and with
`mjcf.from_path` + `mjcf.Physics.from_mjcf_model`, and prints a table by mutation kind:
agreement, false rejections, silent acceptances, compiled differently, crashes (an exception
outside the documented types, a dead worker or a hang) and unclear exceptions; then up to
K examples of each disagreement. Documents run in a worker process so that a crash or a
hang is counted, not fatal. Exits 1 when anything disagrees outside the documented
differences (docs/mujoco_differences.md) and MuJoCo's own crashes.
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing
import random
import sys
import time

from tools import mjcf_differential as differential

_COLUMNS = [v for v in differential.Verdict]
#: Verdicts that are not disagreements of ours.
_NOT_OURS = (differential.Verdict.DOCUMENTED, differential.Verdict.MUJOCO_CRASH)


def _worker(connection) -> None:
    workspace = differential.Workspace()
    try:
        while True:
            document = connection.recv()
            if document is None:
                return
            result = workspace.run(document, lambda: connection.send("mujoco done"))
            connection.send((result.verdict.value, result.detail))
            if result.verdict is differential.Verdict.MUJOCO_CRASH:
                return  # MuJoCo's state may be corrupt: the runner starts a fresh worker
    finally:
        workspace.close()


class _Runner:
    """A worker process that compiles documents; restarted after a crash or a hang."""

    def __init__(self, timeout: float):
        self.timeout = timeout
        self._start()

    def _start(self) -> None:
        self.connection, child = multiprocessing.Pipe()
        self.process = multiprocessing.Process(target=_worker, args=(child,), daemon=True)
        self.process.start()

    def run(self, document) -> differential.Result:
        """Our verdict; MUJOCO_CRASH when the worker died or hung inside MuJoCo's own parse."""
        if not self.process.is_alive():
            self.process.join()
            self._start()
        self.connection.send(document)
        mujoco_done = False
        while self.connection.poll(self.timeout):
            try:
                message = self.connection.recv()
            except EOFError:
                detail = f"worker died (exit code {self.process.exitcode})"
                break
            if message == "mujoco done":
                mujoco_done = True
                continue
            verdict, detail = message
            return differential.Result(differential.Verdict(verdict), detail)
        else:
            detail = f"no answer within {self.timeout} s"
        self.process.kill()
        self.process.join()
        self._start()
        verdict = differential.Verdict.CRASH if mujoco_done else differential.Verdict.MUJOCO_CRASH
        return differential.Result(verdict, detail)

    def close(self) -> None:
        self.connection.send(None)
        self.process.join(5)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("count", type=int, help="number of documents")
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--show", type=int, default=3, help="examples shown per disagreement")
    parser.add_argument("--timeout", type=float, default=30.0, help="seconds per document")
    args = parser.parse_args()

    rng = random.Random(args.seed)
    runner = _Runner(args.timeout)
    table = collections.defaultdict(collections.Counter)
    examples = collections.defaultdict(list)
    start = time.perf_counter()
    for index in range(args.count):
        kind = differential.MUTATION_KINDS[index % len(differential.MUTATION_KINDS)]
        document = differential.document_for(kind, rng)
        result = runner.run(document)
        table[kind][result.verdict] += 1
        if result.verdict is not differential.Verdict.AGREE:
            examples[result.verdict].append((document, result.detail))
    runner.close()
    elapsed = time.perf_counter() - start

    headers = ["kind", "documents"] + [v.value for v in _COLUMNS]
    rows = []
    for kind in differential.MUTATION_KINDS:
        counts = table[kind]
        rows.append([kind, str(sum(counts.values()))] + [str(counts[v]) for v in _COLUMNS])
    totals = collections.Counter()
    for counts in table.values():
        totals.update(counts)
    rows.append(["total", str(sum(totals.values()))] + [str(totals[v]) for v in _COLUMNS])
    widths = [max(len(r[i]) for r in [headers] + rows) for i in range(len(headers))]
    for row in [headers] + rows:
        print("  ".join(cell.rjust(width) for cell, width in zip(row, widths)))
    agreed = totals[differential.Verdict.AGREE]
    fine = agreed + sum(totals[v] for v in _NOT_OURS)
    print(f"\nagreement {agreed}/{args.count} ({100 * agreed / max(args.count, 1):.2f}%); "
          f"outside documented differences and MuJoCo's own crashes {fine}/{args.count} "
          f"({100 * fine / max(args.count, 1):.2f}%); {elapsed:.0f} s")  # fmt: skip
    for verdict, found in examples.items():
        print(f"\n== {verdict.value}: {len(found)}")
        for document, detail in found[: args.show]:
            print(f"-- [{document.kind}] {document.note}\n   {detail[:400]}")
    return 0 if fine == args.count else 1


if __name__ == "__main__":
    sys.exit(main())
