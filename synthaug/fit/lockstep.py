"""Several seeds fitted in lockstep: their optimisers' populations scored together.

A seed's CMA-ES asks for about a dozen candidates at a time, and one call of the render objective has a fixed
cost that such a batch does not amortise (issue 19: 0.31 ms per evaluation at batch 12 against 0.16 at 96).
:func:`run_lockstep` runs each seed's search in its own thread, unchanged; every objective call of a thread
waits until every other running search has asked too (or finished), then one batched
:func:`~synthaug.fit.objective.score_together` scores all the asked populations and each thread goes on with
its own values. A seed's values do not depend on the company it is scored in, so a fit in lockstep is the fit
made alone, value for value (tested); only the wall time changes.

The threads do no torch work of their own (the optimisers are numpy); the scoring runs in the calling thread.
An error in any search, or in the scoring, stops them all and is raised in the caller.
"""

from __future__ import annotations

import queue
import threading
from typing import Any, Callable, Sequence, TypeVar

import numpy as np

from synthaug.fit.objective import RenderObjective, score_together

T = TypeVar("T")


class _Stopped(Exception):
    """Raised in a search's thread when another search or the scoring failed."""


class _Coordinator:
    """The searches' asks are collected under a lock and the calling thread is woken once per round, by the
    last ask (or finish) of the round; each search waits on its own answer queue. Waking the calling thread on
    every ask, or every thread on every ask, cost more than the scoring: a woken thread waits for the GIL while
    another search runs its optimiser step (up to the 5 ms switch interval each time)."""

    def __init__(self, objectives: Sequence[RenderObjective]) -> None:
        self.objectives = list(objectives)
        self.lock = threading.Lock()
        self.ready = threading.Event()
        self.asks: dict[int, np.ndarray] = {}
        self.running = len(self.objectives)
        self.error: BaseException | None = None
        self.outboxes: list[queue.SimpleQueue[Any]] = [queue.SimpleQueue() for _ in self.objectives]

    def evaluate(self, k: int) -> Callable[[np.ndarray], np.ndarray]:
        def ask(u: np.ndarray) -> np.ndarray:
            with self.lock:
                self.asks[k] = u
                if len(self.asks) >= self.running:
                    self.ready.set()
            answer = self.outboxes[k].get()
            if isinstance(answer, _Stopped):
                raise answer
            return answer
        return ask

    def finish(self, k: int, error: BaseException | None = None) -> None:
        with self.lock:
            self.running -= 1
            if error is not None and not isinstance(error, _Stopped) and self.error is None:
                self.error = error
            if self.error is not None or len(self.asks) >= self.running:
                self.ready.set()

    def serve(self) -> None:
        """Score the asked populations together until every search has finished."""
        try:
            while True:
                self.ready.wait()
                with self.lock:
                    self.ready.clear()
                    if self.error is not None:
                        raise self.error
                    if not self.asks:
                        if self.running == 0:
                            return
                        continue
                    if len(self.asks) < self.running:  # not a full round yet
                        continue
                    asks, self.asks = self.asks, {}
                keys = sorted(asks)
                values = score_together([self.objectives[k] for k in keys], [asks[k] for k in keys])
                for k, v in zip(keys, values):
                    self.outboxes[k].put(v)
        except BaseException:
            for box in self.outboxes:  # a search still waiting stops; a finished one never reads it
                box.put(_Stopped())
            raise


def run_lockstep(objectives: Sequence[RenderObjective],
                 searches: Sequence[Callable[[Callable[[np.ndarray], np.ndarray]], T]]) -> list[T]:
    """``[searches[k](evaluate_k) for k]``, run together, where ``evaluate_k(u)`` equals ``objectives[k](u)``.

    Args:
        objectives: one render objective per search (sharing the view cache and distance,
            as :func:`~synthaug.fit.objective.score_together` requires).
        searches: ``search(evaluate) -> result``; each calls its ``evaluate`` as it would call its objective.

    Returns:
        The searches' results, in order.

    Raises:
        The first error of a search or of the scoring (the other searches are stopped).
    """
    if len(objectives) != len(searches):
        raise ValueError(f"{len(objectives)} objectives but {len(searches)} searches")
    if len(objectives) == 1:
        return [searches[0](objectives[0])]
    co = _Coordinator(objectives)
    results: list[Any] = [None] * len(searches)

    def work(k: int) -> None:
        try:
            results[k] = searches[k](co.evaluate(k))
        except BaseException as e:  # noqa: BLE001 - handed to the caller's thread
            co.finish(k, e)
        else:
            co.finish(k)

    threads = [threading.Thread(target=work, args=(k,), daemon=True, name=f"synthaug-fit-{k}")
               for k in range(len(searches))]
    for t in threads:
        t.start()
    try:
        co.serve()
    finally:
        for t in threads:
            t.join(timeout=60)
    return results
