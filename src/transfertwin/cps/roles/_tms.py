"""The Transport Module System on its node: the owner of the object ledger and of the
operations (its `OrderBook`), and the dispatcher that runs them: the plan (the state to
load the object in: the twin's ranking and the floor's own transfers), the auction among
the idle modules, the assignment and the watch over the module's lease (docs/architecture.md,
"Operation").

An order is checked against the ledger and its object reserved in one step; it gets an id
that is unique on the floor across restarts (the counter is persisted), then waits for an
idle transport module that the knowledge graph lists as online. The module reports every
step, every moved object and the result (`ReportProgress`); the TMS writes each report to
its state file before it acknowledges it, so a report is applied exactly once whatever
crashes.

Faults: a module whose lease expires while it holds an operation fails that operation with
the step it was in. A failure in the middle of a transfer leaves the object's place
unknown: the ledger then says ``unknown, last seen at X`` with the operation that lost it,
orders for it are refused until an operator states where it is (`Locate`) or a late report
of the module settles it. Nothing is dropped: a report for an operation that has already
ended still moves the object, and is kept in the operation's history.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
from typing import TYPE_CHECKING, Any

from transfertwin.cps.aas import Capability, object_properties
from transfertwin.cps.dispatch import (
    Bid,
    OrderBook,
    choose,
    fallback,
    learning_alone_states,
    object_needs,
    order_view,
    rerank,
    twin_words,
)
from transfertwin.cps.node import Partner, Role, find_partner_ids, find_partners
from transfertwin.cps.opcua import OperationRefused

if TYPE_CHECKING:
    from transfertwin.cps.node import AssetNode

__all__ = ["TmsRole"]

log = logging.getLogger("transfertwin.cps")

#: Seconds the TMS waits for the Experiment Manager's on-the-fly predictions of an object.
PREDICT_TIMEOUT_S = 900.0
#: Seconds the TMS keeps the graph's answer to "who realises Transport, with which
#: constraints" (online or not comes from the graph's Status at every look): orders that
#: wait for a module look every 0.5 s, and a query costs the graph ~14 ms on a large floor.
MOVERS_TTL_S = 2.0


class TmsRole(Role):
    """The Transport Module System."""

    def __init__(self, node: AssetNode) -> None:
        super().__init__(node)
        self.book = OrderBook(node.floor, self.state.data, self.state.save)
        self.ledger, self.ops = self.book.ledger, self.book.ops
        self.policy = node.floor.operation.policy
        self._claimed: dict[str, str] = {}  # module -> operation
        self._movers: tuple[float, list[Partner]] = (float("-inf"), [])  # (when, answer)
        self._done: dict[str, asyncio.Event] = {}

    def initial(self) -> dict[str, Any]:
        return OrderBook.initial(self.node.floor)

    def handlers(self) -> dict[str, Any]:
        return {"SubmitTransportOperation": self._submit, "OrderTo": self._order_to,
                "Orders": self._orders, "Kpis": self._kpis, "OperationStatus": self._status,
                "ReportProgress": self._progress, "Ledger": self._ledger,
                "Locate": self._locate}  # fmt: skip

    async def start(self) -> None:
        self.book.pending |= set(self.node.floor.units) | {o for o, _ in self.node.floor.objects}
        for op_id, op in self.ops.items():
            if op["state"] != "finished":
                log.info("TMS: resuming %s (%s)", op_id, op["phase"])
                if op.get("module"):
                    self._claimed[op["module"]] = op_id
                self.node.spawn(self._run(op_id))
        await self.set("Policy", self.policy)
        # weigh the floor's objects (`object_needs`: the mesh library) off the event loop
        self.node.spawn(asyncio.to_thread(
            lambda: [object_needs(o) for o, _ in self.node.floor.objects]))  # fmt: skip
        await self._counters()
        self.node.spawn(self._publisher())

    async def live(self) -> dict[str, Any]:
        return {"state": "busy" if self.book.running() else "idle"}

    # -- orders ---------------------------------------------------------------------------
    async def _submit(self, source: str, target: str, obj: str) -> str:
        """An order naming its source and target unit."""
        return await self._accept(obj, target, source)

    async def _order_to(self, obj: str, destination: str) -> str:
        """An order by destination (a unit or a group of the floor file): the source is
        where the object is once its earlier orders have ended."""
        return await self._accept(obj, destination, None)

    async def _accept(self, obj: str, destination: str, source: str | None) -> str:
        """Check and queue an order (`OrderBook.accept`), then run it. Refused when modules
        are online but the constraints of none admit the object (`_modules`)."""
        modules = await self._modules(obj)
        online = [m for m in modules or () if m["online"]]
        if online and not any(m["admits"] for m in online):
            raise OperationRefused(
                f"no online transport module carries {obj} "
                f"({', '.join(f'{k} {v:g}' for k, v in object_needs(obj).items())}): the "
                "constraints of their transport capability do not admit it",
                status="BadResourceUnavailable", argument="object")  # fmt: skip
        op_id = self.book.accept(obj, destination, source, modules)
        await self._counters()
        self.node.spawn(self._run(op_id))
        return op_id

    async def _orders(self) -> str:
        return json.dumps([order_view(op) for op in self.ops.values()])

    async def _kpis(self) -> str:
        doc = self.book.kpi_doc(self.policy)
        doc["predictions_unanswered"] = self.state.data.get("predictions_unanswered", 0)
        return json.dumps(doc)

    async def _status(self, op_id: str) -> str:
        return json.dumps(self.book.status(op_id))

    async def _ledger(self) -> str:
        return json.dumps(self.book.ledger_doc())

    async def _locate(self, obj: str, holder: str) -> bool:
        """An operator says where `obj` lies (`OrderBook.locate`). A module whose own record
        still says it carries `obj` (a delivery it gave up on) is told it does not any more
        (``ReleaseObject``), so that it takes orders again; one that does not answer makes
        the TMS refuse, saying what to do."""
        self.book.check_locate(obj, holder)
        carriers = {m["id"] for m in await self._modules() or () if obj in m.get("possesses", ())}
        if self.ledger.location(obj) in {m.asset_id for m in self.node.floor.modules}:
            carriers.add(self.ledger.location(obj))
        for module in sorted(carriers):
            try:
                await asyncio.wait_for(self.node.peers.call(module, "ReleaseObject", obj), 10)
            except OperationRefused:
                raise
            except Exception as exc:
                raise OperationRefused(
                    f"{module} carries {obj} by its own record and does not answer "
                    f"({type(exc).__name__}); start {module} again, then locate {obj}",
                    status="BadResourceUnavailable", argument="object") from None
        self.book.locate(obj, holder)
        return True

    # -- execution ------------------------------------------------------------------------
    async def _modules(self, obj: str | None = None) -> list[dict[str, Any]] | None:
        """The transport modules as the knowledge graph knows them (None: graph away): the
        assets that realise Transport, whatever their class (`find_partners`), with what
        the graph's ``Status`` says of them and ``admits``: whether the constraints of
        their transport capability admit `obj` (`object_needs`: its mass; True without)."""
        movers = await self._transport_partners()
        assets = await self.node.graph_status() if movers is not None else None
        if assets is None:
            return None
        needs = object_needs(obj) if obj else {}
        admits = {p.asset_id: p.admits(needs) for p in movers or ()}
        return [{**a, "admits": admits[a["id"]]} for a in assets if a["id"] in admits]

    async def _transport_partners(self) -> list[Partner] | None:
        """The assets that realise Transport, online or not (`find_partners`), as the graph
        answered within the last `MOVERS_TTL_S` (None: the graph is away)."""
        when, movers = self._movers
        if time.monotonic() - when < MOVERS_TTL_S:
            return movers
        found = await find_partners(self.node, Capability.TRANSPORT, online=False)
        if found is not None:
            self._movers = (time.monotonic(), found)
        return found

    def _eligible(self, op: dict[str, Any], modules: list[dict[str, Any]]) -> list[str]:
        """Of `modules` (`_modules`), the online, idle, unclaimed ones that may take `op`:
        the carrier alone for an object on a module; else those that carry nothing
        (objects travel one at a time)."""
        carrier = op["source"] if op["source"] not in self.node.floor.units else None
        out = []
        for m in modules:
            if carrier is not None and m["id"] != carrier:
                continue
            if carrier is None and self.book.carried_by(m["id"]):
                continue
            if m["online"] and m["admits"] and m["state"] == "idle" \
                    and m["id"] not in self._claimed:  # fmt: skip
                out.append(m["id"])
        return out

    async def _allocate(self, op_id: str) -> tuple[str, str, dict[str, Any]]:
        """Run the auction for `op_id` (`_dispatch`) until a module wins; claim it.
        Returns (module, target unit, the bids' record)."""

        op = self.ops[op_id]
        p = (op.get("plan") or {}).get("prediction") or {}
        while True:
            # the destination's units whose belts are free (or will be), the source excepted
            targets = [t for t in op["targets"] if t != op["source"] and not self.book.occupied(t)]
            if self.policy != "predictive":
                targets = targets[:1]
            if not targets:
                held = "; ".join(f"{t} holds {', '.join(self.book.ledger.objects_at(t))}"
                                 for t in op["targets"] if t != op["source"])  # fmt: skip
                self._waiting(op, f"the destination is occupied ({held}): order that away")
                await asyncio.sleep(0.5)
                continue
            order = json.dumps({"operation": op_id, "object": op["object"],
                                "source": op["source"], "targets": targets})  # fmt: skip
            modules = await self._modules(op["object"]) or []
            eligible = self._eligible(op, modules)

            async def ask(m: str, order: str = order) -> Bid | None:
                try:
                    doc = json.loads(await asyncio.wait_for(
                        self.node.peers.call(m, "Bid", order), 10))  # fmt: skip
                except Exception as exc:
                    log.debug("TMS: no bid from %s for %s: %s", m, op_id, exc)
                    return None
                return Bid(doc["module"], doc["eta_s"])

            bids = [b for b in await asyncio.gather(*(ask(m) for m in eligible)) if b]
            bids = [b for b in bids if b.module not in self._claimed]
            if bids:
                module, target, cost = choose(bids, self.policy, p.get("p", p.get("share")))
                self._claimed[module] = op_id
                record = {"bids": {b.module: dict(b.eta_s) for b in bids},
                          "winner": module, "target": target, "cost_s": round(cost, 3)}
                return module, target, record
            if not eligible:
                self._why_no_module(op, modules)
            await asyncio.sleep(0.5)

    def _why_no_module(self, op: dict[str, Any], modules: list[dict[str, Any]]) -> None:
        """Say in `op`'s history why no module of `modules` (the auction round's read of
        the graph) bids when every online one carries an object (it waits until one is
        ordered onward or located)."""
        if op["source"] not in self.node.floor.units:
            return  # the carrier itself moves it on once it is idle
        online = [m["id"] for m in modules if m["online"]]
        held = {m: self.book.carried_by(m) for m in online}
        if online and all(held.values()):
            self._waiting(op, "every transport module carries an object (" + "; ".join(
                f"{m} carries {', '.join(o)}" for m, o in held.items()) + "): order those "
                "onward or locate them")  # fmt: skip

    def _waiting(self, op: dict[str, Any], why: str) -> None:
        """Put why `op` waits in its history and the log, once per reason."""
        if op.get("waiting") == why:
            return
        op["waiting"] = why
        op["history"].append([time.time(), f"waiting: {why}"])
        self.book.save()
        log.info("TMS: %s waiting: %s", op["operation"], why)

    async def _after(self, op_id: str) -> bool:
        """Wait for the order `op_id` chains after; then take the object from where it is
        (`OrderBook.chain`). False when the order ended here."""
        op = self.ops[op_id]
        if op.get("after") is None or op["source"] is not None:
            return True
        prev = op["after"]
        if self.ops[prev]["state"] != "finished":
            await self._done.setdefault(prev, asyncio.Event()).wait()
        if not self.book.chain(op_id):
            self._ended(op_id)
            return False
        return True

    async def _plan(self, op: dict[str, Any]) -> dict[str, Any]:
        """The state to load the object in: the twin's best for it (predictive; not for
        an object already on a module), else the default. With `learn` (the default), the
        twin's shares are updated with the floor's own transfers of the object (`_learn`);
        with ``twin = false`` the states are ranked by those transfers alone (learning
        alone, from a flat prior: the default state first)."""
        if self.policy != "predictive":
            return {"policy": self.policy, "state": None}
        if op["source"] not in self.node.floor.units:
            return {"policy": self.policy, "state": None,
                    "note": "loaded already: the state it lies in is kept"}  # fmt: skip
        if self.node.floor.operation.twin:
            preds = await self._predictions(op["object"], op["operation"])
        else:  # learning alone: every state of the grid, ranked by the floor's transfers
            preds = learning_alone_states()
        if not preds:
            return {"policy": self.policy, "state": None,
                    "note": "no prediction for this object: default state"}  # fmt: skip
        keys = ("face", "conveyor", "theta_deg")
        if self.node.floor.operation.learn:

            evidence = self.state.data.setdefault("evidence", {}).get(op["object"], {})
            ranked = rerank(preds, evidence)
            after = fallback(preds, evidence, ranked[0])
        else:
            ranked = preds
            after = {k: preds[1][k] for k in keys} if len(preds) > 1 else None
        best = ranked[0]
        # a failed pick-up is tried again in `fallback` (the module puts the object down anew)
        return {"policy": self.policy, "state": {k: best[k] for k in keys},
                "prediction": best, "next_best": ranked[1] if len(ranked) > 1 else None,
                "fallback": after}  # fmt: skip

    async def _predictions(self, obj: str, op_id: str) -> list[dict[str, Any]]:
        """The twin's ranked states for `obj`: those a calibration campaign published in
        the object's AAS (``PredictionsJson``; a newer campaign replaces what was cached);
        else cached; else the Experiment Manager's (from the floor's study store, which its
        bundle holds, or its on-the-fly experiments; each prediction names its
        ``source``). When it does not answer, the operation's history and the log say so,
        and ``Kpis`` counts it (``predictions_unanswered``)."""

        cache = self.state.data.setdefault("predictions", {})
        published = await self._published(obj)
        if published is not None:
            campaign, states = published
            if self.state.data.setdefault("prediction_campaign", {}).get(obj) != campaign:
                self.state.data["prediction_campaign"][obj] = campaign
                cache[obj] = states
                self.ops[op_id]["history"].append(
                    [time.time(), f"predictions of {obj} from its AAS (campaign {campaign})"])
                self.book.save()
            return cache[obj]
        if obj in cache:
            return cache[obj]
        self.ops[op_id]["history"].append(
            [time.time(), f"asking the Experiment Manager to predict {obj}"])
        try:
            preds = await asyncio.wait_for(self._ask_em(obj), PREDICT_TIMEOUT_S)
        except Exception as exc:
            log.warning("TMS: no prediction for %s (the Experiment Manager: %r): default state",
                        obj, exc)  # fmt: skip
            self.state.data["predictions_unanswered"] = \
                self.state.data.get("predictions_unanswered", 0) + 1
            self.ops[op_id]["history"].append(
                [time.time(), f"no prediction ({type(exc).__name__}: {exc}): default "
                              "state"])  # fmt: skip
            return []
        cache[obj] = preds
        self.book.save()
        return preds

    async def _published(self, obj: str) -> tuple[str, list[dict[str, Any]]] | None:
        """(campaign, ranked states) a calibration campaign published in `obj`'s AAS, or
        None: none yet, or the object's server does not answer (the EM's `Predict` answers
        from the same campaign)."""
        try:
            doc = json.loads(await asyncio.wait_for(
                self.node.peers.read(obj, "PredictionsJson"), 2) or "{}")  # fmt: skip
        except Exception as exc:
            log.debug("TMS: %s's published predictions not read: %r", obj, exc)
            return None
        states = doc.get("states") if isinstance(doc, dict) else None
        if not states or not doc.get("campaign"):
            return None
        return str(doc["campaign"]), states

    async def _ask_em(self, obj: str) -> list[dict[str, Any]]:
        """Poll the Experiment Manager's `Predict` until its experiments are done: the
        asset that realises Experiment (`find_partner_ids`; the first by id if several)."""
        spec = self.node.floor.operation
        while True:
            managers = await find_partner_ids(self.node, Capability.EXPERIMENT)
            if not managers:
                raise ConnectionError("no online asset realises Experiment")
            em = managers[0]
            answer = await asyncio.wait_for(self.node.peers.call(
                em, "Predict", obj, spec.runs, self.node.cfg.seed), 10)  # fmt: skip
            if answer:
                return json.loads(answer)
            await asyncio.sleep(1.0)

    async def _run(self, op_id: str) -> None:
        """`_execute`; an order it could not run ends as a fault of the floor with the error
        as its reason (in its history, the log and the KPIs), never left queued."""
        try:
            await self._execute(op_id)
        except asyncio.CancelledError:
            raise
        except Exception as exc:
            log.exception("TMS: %s could not run", op_id)
            op = self.ops[op_id]
            if op["state"] != "finished":
                op["history"].append([time.time(), f"error: {type(exc).__name__}: {exc}"])
                self._finish(op_id, {"status": f"error: {type(exc).__name__}: {exc}",
                                     "failed_step": op.get("phase"), "fault": True})  # fmt: skip
                await self._counters()

    async def _execute(self, op_id: str) -> None:

        op = self.ops[op_id]
        done = self._done.setdefault(op_id, asyncio.Event())
        if op["module"] is None:
            if not await self._after(op_id):
                return
            if "plan" not in op:
                op["plan"] = await self._plan(op)
                if op["plan"].get("state"):
                    st, pr = op["plan"]["state"], op["plan"]["prediction"]
                    op["history"].append([time.time(), (
                        f"load {st['face']}/{st['conveyor']}/{st['theta_deg']} deg: "
                        + (twin_words(pr) if pr.get("n") else "no twin")
                        + (f"; with the floor's transfers p = {pr['p']:.2f} (pick-up "
                           f"{pr['p_pickup']:.2f}, delivery {pr['p_delivery']:.2f})"
                           if "p" in pr else ""))])  # fmt: skip
                self.book.save()
        while op["module"] is None:
            module, target, record = await self._allocate(op_id)
            try:
                await asyncio.wait_for(self.node.peers.call(
                    module, "AssignOperation", op_id, op["source"], target, op["object"],
                    json.dumps(op["plan"])), 15)  # fmt: skip
            except OperationRefused as exc:
                if module == op["source"] and exc.status == "BadNotFound":
                    # the ledger says the module carries it, the module says it does not
                    self._claimed.pop(module, None)
                    self._finish(op_id, {"status": "failed at delivery", "failed_step": "assigned",
                                         "reason": f"{exc.reason}: its place is not known",
                                         "location_unknown": True})  # fmt: skip
                    return
                log.info("TMS: %s not assigned to %s: %s", op_id, module, exc)
                self._claimed.pop(module, None)
                await asyncio.sleep(0.5)
                continue
            except (OSError, TimeoutError, ConnectionError) as exc:
                log.info("TMS: %s not assigned to %s: %s", op_id, module, exc)
                self._claimed.pop(module, None)
                await asyncio.sleep(0.5)
                continue
            op.update(module=module, target=target, state="running", phase="assigned",
                      assigned=time.time(), auction=record)  # fmt: skip
            op["history"].append([time.time(), f"assigned to {module} for {target} "
                                               f"(expected {record['cost_s']:.0f} s)"])
            self.book.save()
            log.info("TMS: %s allocated to %s", op_id, module)
        await self._watch(op_id, done)

    async def _watch(self, op_id: str, done: asyncio.Event) -> None:
        """Wait for the result; fail the operation if its module stays offline.

        A module whose lease expired may only have been slow: the operation fails once the
        module has been offline for one more lease period (a module that restarted reports
        the failure itself, with the step it was in).
        """
        op = self.ops[op_id]
        module = op["module"]
        grace = self.node.cfg.lease_s
        offline_since: float | None = None
        while op["state"] != "finished":
            try:
                await asyncio.wait_for(done.wait(), 1.0)
                continue
            except TimeoutError:
                pass
            modules = await self.node.graph_status()
            if modules is None:
                continue  # the graph is away: cannot tell, keep waiting
            if module in {m["id"] for m in modules if m["online"]}:
                offline_since = None
                continue
            offline_since = offline_since or time.monotonic()
            if time.monotonic() - offline_since >= grace and op["state"] != "finished":
                step = op["phase"]
                self._finish(op_id, {
                    "status": f"failed while {step}", "failed_step": step,
                    "reason": f"{module} went offline (lease expired) while {step}",
                    "location_unknown": step == "transferring", "fault": True,
                })  # fmt: skip

    def _finish(self, op_id: str, result: dict[str, Any]) -> None:
        self.book.finish(op_id, result)
        self._ended(op_id)

    def _ended(self, op_id: str) -> None:
        """`op_id` has ended: its module is free, its waiters wake, the counters follow."""
        module = self.ops[op_id].get("module")
        if module:
            self._claimed.pop(module, None)
        self.book.pending.add(self.ops[op_id]["object"])  # its AAS shows the outcome
        self._done.setdefault(op_id, asyncio.Event()).set()
        self.node.spawn(self._counters())

    async def _progress(self, op_id: str, payload: str) -> bool:
        """A module's report: applied once (the TMS saves it before acknowledging)."""
        if self.book.progress(op_id, json.loads(payload)):
            self._ended(op_id)
        return True

    # -- publication ----------------------------------------------------------------------
    async def _counters(self) -> None:
        running = self.book.running()
        await self.set("QueuedOperations", running)
        await self.set("CompletedOperations", len(self.ops) - running)
        k = self.book.kpi_doc(self.policy)
        low, high = k["success_share_ci95"]
        for prop, value in (("OperationsPerHour", k["operations_per_hour"]),
                            ("SuccessShare", k["success_share"]), ("SuccessShareLow", low),
                            ("SuccessShareHigh", high), ("MeanLeadTime", k["mean_lead_time_s"])):
            await self.set(prop, float(value) if value is not None else float("nan"))
        await self.set("KpisJson", json.dumps(k))

    async def _publisher(self) -> None:
        """Bring the units' possessions and the objects' PossessedBy (and what their AAS
        shows of their transfers, `object_properties`) in line with the ledger, retrying
        whatever could not be written (an asset that is away)."""
        units = set(self.node.floor.units)
        while True:
            for aid in sorted(self.book.pending):
                try:
                    if aid in units:
                        objs = [o for o in self.ledger.objects_at(aid)
                                if o not in self.book.data["unknown"]]  # fmt: skip
                        await asyncio.wait_for(self.node.peers.call(
                            aid, "SetPossessedObjects", ",".join(objs)), 5)  # fmt: skip
                    elif aid in self.ledger.locations():
                        lost = aid in self.book.data["unknown"]
                        where = "" if lost else self.ledger.location(aid)
                        await asyncio.wait_for(self.node.peers.write(aid, "PossessedBy", where), 5)
                        for prop, value in object_properties(aid, self.ops.values()).items():
                            await asyncio.wait_for(self.node.peers.write(aid, prop, value), 5)
                    self.book.pending.discard(aid)
                except Exception as exc:
                    log.debug("TMS: %s not updated yet: %s", aid, exc)
            await asyncio.sleep(0.5)
