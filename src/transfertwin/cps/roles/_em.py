"""The Experiment Manager on its node: single experiments against a unit (``RunExperiment``:
E^V, or E^P on a plant's physical unit), studies on request (``StartStudy``,
``StopStudy``, ``StudyStatus``; docs/architecture.md, "Studies through the Experiment
Manager"), calibration campaigns on the floor's physical units (``StartCampaign``,
``StopCampaign``, ``CampaignStatus``; "Calibration campaigns") and the twin's predictions
(``Predict``: the latest finished campaign's, else the floor's study's, else virtual
experiments now).

A study runs as a job of this node (`StudyJob`: a thread that runs the study in a process
of its own); its progress and ETA are the ``Study*`` OperationalData properties. What the
manager was asked last is persisted: a study that was running when the process ended (a
crash, ``cps down``) resumes when it comes back; one stopped with ``StopStudy`` stays
stopped until ``StartStudy`` names it again.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from pathlib import Path
from typing import Any

from transfertwin._errors import InputError
from transfertwin.cps.aas import AssetKind
from transfertwin.cps.apps import (
    CampaignJob,
    CampaignRequest,
    StudyJob,
    StudyRequest,
    UnitUnavailableError,
    record_store,
    study_opcua_values,
)
from transfertwin.cps.dispatch import (
    campaign_advice,
    campaign_predictions,
    study_predictions,
    virtual_predictions,
)
from transfertwin.cps.hal import load_scene
from transfertwin.cps.node import Role
from transfertwin.cps.opcua import OpcUaUnitHAL, OperationRefused
from transfertwin.cps.roles._plant_unit import PLANT_LOG, append_plant_log, physical_record

__all__ = ["ExperimentRole"]

#: Worker processes of the on-the-fly predictions (`Predict`).
PREDICT_WORKERS = 2

log = logging.getLogger("transfertwin.cps")

#: Statuses of a physical unit that offers no experiment cycle (a unit behind a HAL
#: gateway without ``RunTransfer``): a campaign leaves it out.
_NO_CYCLE = frozenset({"BadMethodInvalid", "BadNodeIdUnknown", "BadNotImplemented"})

#: Seconds `StopStudy` waits for the batch in flight before it answers.
STOP_WAIT_S = 120.0


class ExperimentRole(Role):
    """The Experiment Manager: runs E^V against a unit through that unit's OPC UA interface;
    the virtual unit's physics runs here and mirrors its belt commands (`MirroredUnitHAL`).
    Runs studies into result stores (`StudyJob`)."""

    def __init__(self, node) -> None:
        super().__init__(node)
        self.job = None  # the last StudyJob
        self._task: asyncio.Task | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._start_lock = asyncio.Lock()
        self._pool = None  # the warm worker processes of `Predict` (`WarmPool`)
        self._warming: asyncio.Task | None = None
        self.campaign: CampaignJob | None = None  # the last campaign started here
        self._campaign_task: asyncio.Task | None = None
        self._published_preds: tuple[str, dict[str, Any]] | None = None  # (id, predictions)

    def initial(self) -> dict[str, Any]:
        # study: {"request": text, "store": path, "want": running|stopped|finished|failed}
        # campaign: {"request": text, "id": id, "want": …}; published: the last finished
        # campaign's id, whose predictions `Predict` answers with
        return {"study": None, "campaign": None, "published": None}

    def handlers(self) -> dict[str, Any]:
        return {"RunExperiment": self._run, "StartStudy": self._start_study,
                "StopStudy": self._stop_study, "StudyStatus": self._study_status,
                "Predict": self._predict, "StartCampaign": self._start_campaign,
                "StopCampaign": self._stop_campaign,
                "CampaignStatus": self._campaign_status}  # fmt: skip

    async def _predict(self, obj: str, runs: int, seed: int) -> str:
        """The twin's ranked states for `obj`: from the floor's study store when it has
        them (`_from_study`), else from virtual experiments (`cps.dispatch.
        virtual_predictions`; the TMS asks here, it reads no store itself). These take longer
        than a request may: the first call starts them and answers '' (running), a later
        call with the same arguments answers the JSON list once they are done."""
        if obj not in {o for o, _ in self.node.floor.objects}:
            raise ValueError(f"{obj!r} is not an object of this floor")
        if not 1 <= int(runs) <= 100:
            raise ValueError(f"runs must be 1..100, got {runs}")
        if (found := await self._from_campaign(obj)) is not None:
            return found
        if (found := await self._from_study(obj)) is not None:
            return found
        jobs = self.__dict__.setdefault("_predicting", {})
        key = (obj, int(runs), int(seed))
        job = jobs.get(key)
        if job is None:
            job = jobs[key] = asyncio.get_running_loop().create_task(self._predict_now(*key))
        if not job.done():
            return ""
        if job.exception() is not None:
            del jobs[key]  # asked again: tried again
            raise job.exception()
        return job.result()

    async def _from_study(self, obj: str) -> str | None:
        """`obj`'s ranked states from the floor's study store (in this asset's bundle,
        ``[runtime] study``), as `_predict` answers them; None when the floor has none, or
        it cannot be read or holds no state of `obj` (both logged: the answer then comes
        from virtual experiments, and says so in its ``source``)."""
        store = self.node.cfg.study_file
        if store is None:
            return None
        try:
            found = await asyncio.to_thread(study_predictions, store, obj)
        except Exception as exc:
            log.warning("EM: study store %s not readable (%s): %s from virtual experiments",
                        store, exc, obj)  # fmt: skip
            return None
        if not found:
            log.warning("EM: study store %s has no state of %s: virtual experiments",
                        store.name, obj)  # fmt: skip
            return None
        return json.dumps([p.as_dict() for p in found])

    async def _from_campaign(self, obj: str) -> str | None:
        """`obj`'s ranked states from the latest finished campaign (its
        ``predictions.json``), or None (no campaign, or it did not predict `obj`)."""
        published = self.state.data.get("published")
        if not published:
            return None
        if self._published_preds is None or self._published_preds[0] != published:
            path = self._campaign_dir(published) / "predictions.json"
            try:
                doc = json.loads(await asyncio.to_thread(path.read_text))
            except (OSError, json.JSONDecodeError) as exc:
                log.warning("EM: predictions of campaign %s not readable: %s", published, exc)
                return None
            self._published_preds = (published, doc["predictions"])
        found = self._published_preds[1].get(obj)
        return json.dumps(found) if found else None

    async def _predict_now(self, obj: str, runs: int, seed: int) -> str:

        await self.set("State", "predicting")
        try:
            # on worker processes: never beside another experiment in this process's threads
            # (two threads on one object's compiled model crash MuJoCo); kept warm between
            # requests (started with the node), so a request pays for its experiments only
            pool = await self._warm_pool()
            preds = await asyncio.to_thread(
                virtual_predictions, obj, runs, seed, load_scene(), executor=pool,
                sampling=self.node.floor.operation.sampling)  # fmt: skip
        finally:
            await self.set("State", "idle")
        return json.dumps([p.as_dict() for p in preds])

    async def _warm_pool(self):
        """The started `WarmPool` of the predictions (started once; a failed start is
        tried again by the next request)."""
        from transfertwin.study.experiment import WarmPool

        if self._pool is None:
            self._pool = WarmPool(PREDICT_WORKERS)
        if self._warming is None or (self._warming.done() and self._warming.exception()):
            self._warming = asyncio.get_running_loop().create_task(
                asyncio.to_thread(self._pool.start)
            )
        await asyncio.shield(self._warming)
        return self._pool

    async def start(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._warming = None
        op = self.node.floor.operation
        if op.policy == "predictive" and op.twin:
            # the predictions' worker processes start now, beside the node, not on the
            # first order's request (a floor that never asks starts none)
            task = self._loop.create_task(self._warm_pool())
            task.add_done_callback(lambda t: t.cancelled() or t.exception())
        campaign = self.state.data.get("campaign")
        if campaign and campaign.get("want") == "running":  # running when we went down
            log.info("EM: resuming campaign %s", campaign["id"])
            try:
                await self._launch_campaign(campaign["request"])
            except (InputError, ValueError) as exc:
                log.warning("EM: the campaign cannot resume: %s", exc)
                campaign["want"] = "failed"
                self.state.save()
        study = self.state.data.get("study")
        if study and study.get("want") == "running":  # it was running when we went down
            log.info("EM: resuming the study into %s", study["store"])
            try:
                await self._launch(study["request"], Path(study["store"]))
            except InputError as exc:
                log.warning("EM: the study cannot resume: %s", exc)
                study["want"] = "failed"
                self.state.save()

    async def stop(self) -> None:
        if self.job is not None:  # (the node has cancelled the task that awaited it)
            self.job.stop()  # the persisted wish stays 'running': it resumes on restart
            await asyncio.to_thread(self.job.wait, 10.0)
        if self.campaign is not None:  # likewise: journaled, resumed on restart
            self.campaign.stop()
            await asyncio.to_thread(self.campaign.wait, 10.0)
        if self._pool is not None:
            await asyncio.to_thread(self._pool.close)

    async def live(self) -> dict[str, Any]:
        running = self._task is not None and not self._task.done()
        if self._campaign_task is not None and not self._campaign_task.done():
            return {"state": "running_campaign"}
        return {"state": "running_study" if running else "idle"}

    # -- calibration campaigns ------------------------------------------------------------
    def _campaign_dir(self, campaign_id: str) -> Path:
        return (self.node.cfg.state_dir / "campaigns" / campaign_id).resolve()

    def _physical_units(self) -> list[str]:
        return sorted(
            d.asset_id
            for d in self.node.descriptors.values()
            if d.kind is AssetKind.PHYSICAL and d.role_class == "transfer_unit"
        )

    async def _start_campaign(self, request_json: str) -> str:
        """Start (or resume) a campaign from its JSON request; '' resumes the last one."""
        running = self._campaign_task is not None and not self._campaign_task.done()
        saved = self.state.data.get("campaign")
        if not request_json.strip():
            if saved is None:
                raise ValueError("no campaign to resume: give a request")
            request_json = saved["request"]
        try:
            request = CampaignRequest.parse(request_json, [o for o, _ in self.node.floor.objects])
        except InputError as exc:
            raise ValueError(str(exc)) from None
        if running:
            if self.campaign.request.campaign_id == request.campaign_id:
                return json.dumps(self.campaign.status())
            raise ValueError(f"campaign {self.campaign.request.campaign_id} is running: "
                             "stop it first")  # fmt: skip
        if self._task is not None and not self._task.done():
            raise ValueError("a study is running: a campaign waits until it ends")
        if saved is not None and saved["id"] == request.campaign_id and \
                saved["want"] == "finished":  # fmt: skip
            return await self._campaign_status()  # done: its outputs stand (a new seed reruns)
        await self._launch_campaign(request_json, request)
        return json.dumps(self.campaign.status())

    async def _launch_campaign(self, text: str, request: CampaignRequest | None = None) -> None:
        if request is None:
            request = CampaignRequest.parse(text, [o for o, _ in self.node.floor.objects])
        units = self._physical_units()
        loop = asyncio.get_running_loop()

        def run_one(unit: str, obj: str, face: str, conveyor: str, theta: int) -> dict:
            future = asyncio.run_coroutine_threadsafe(
                self._cycle(unit, obj, face, conveyor, theta), loop)  # fmt: skip
            try:
                return future.result(timeout=600)
            except OperationRefused as exc:  # a unit that never will: it goes on without
                if "has no station" in exc.reason or exc.status in _NO_CYCLE:
                    raise UnitUnavailableError(unit, exc.reason) from None
                raise

        job = CampaignJob(request, self._campaign_dir(request.campaign_id), run_one, units,
                          campaign_predictions, on_update=self._campaign_published)  # fmt: skip
        self.state.data["campaign"] = {"request": text, "id": request.campaign_id,
                                       "want": "running"}  # fmt: skip
        self.state.save()
        self.campaign = job
        self._campaign_task = self.node.spawn(self._run_campaign(job))

    async def _run_campaign(self, job: CampaignJob) -> None:
        final = await asyncio.to_thread(job.run)
        saved = self.state.data.get("campaign")
        if saved is not None and self.campaign is job and final["state"] != "stopped":
            saved["want"] = final["state"]
            if final["state"] == "finished":
                self.state.data["published"] = job.request.campaign_id
                await self._publish_predictions(job)
            self.state.save()
        log.info("EM: campaign %s %s (%d E^P, %.0f s of floor time)%s", final["campaign"],
                 final["state"], final["plant_experiments"], final["floor_s"],
                 f": {final['error']}" if final["error"] else "")  # fmt: skip

    async def _publish_predictions(self, job: CampaignJob) -> None:
        """Each object's predictions into its AAS (``PredictionsJson``), best effort: an
        object that is away gets them from `Predict` all the same."""
        path = job.folder / "predictions.json"
        doc = json.loads(await asyncio.to_thread(path.read_text))
        advice = await asyncio.to_thread(campaign_advice, job.folder, list(doc["predictions"]))
        for obj, preds in doc["predictions"].items():
            value = json.dumps({"campaign": doc["campaign"], "leg": doc["leg"],
                                "advice": advice.get(obj, ""),
                                "best": preds[0] if preds else None,
                                "worst": preds[-1] if preds else None,
                                "states": preds})  # fmt: skip
            try:
                await asyncio.wait_for(self.node.peers.write(obj, "PredictionsJson", value), 5)
            except Exception as exc:
                log.info("EM: %s's AAS not updated with the campaign's predictions: %s",
                         obj, exc)  # fmt: skip

    def _campaign_published(self, status: dict[str, Any]) -> None:
        """From the campaign's thread: its progress into ``State``'s neighbours."""
        if self._loop is not None and not self._loop.is_closed():
            line = f"{status['state']}: {status['stage']} {status['done']}/{status['total']}"
            asyncio.run_coroutine_threadsafe(self._set_quiet("CampaignProgress", line),
                                             self._loop)  # fmt: skip

    async def _set_quiet(self, prop: str, value: Any) -> None:
        with contextlib.suppress(Exception):  # a server going down mid-update
            await self.set(prop, value)

    async def _stop_campaign(self) -> str:
        if self.campaign is None:
            raise ValueError("no campaign has been started")
        saved = self.state.data.get("campaign")
        if self._campaign_task is not None and not self._campaign_task.done():
            if saved is not None:
                saved["want"] = "stopped"
                self.state.save()
            self.campaign.stop()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.shield(self._campaign_task), STOP_WAIT_S)
        return json.dumps(self.campaign.status())

    async def _campaign_status(self) -> str:
        """The last campaign's status, and ``floor_s_all``: the floor time of every
        campaign this EM has run (their E^P's cycle times), the KPIs' calibration cost."""
        total = await asyncio.to_thread(self._campaigns_floor_s)
        if self.campaign is not None:
            return json.dumps({**self.campaign.status(), "floor_s_all": total})
        saved = self.state.data.get("campaign")
        if saved is None:
            return json.dumps({"state": "none", "campaign": None, "floor_s_all": total})
        path = self._campaign_dir(saved["id"]) / "campaign.json"
        try:  # the last status it wrote, before this process started
            st = json.loads(await asyncio.to_thread(path.read_text))
        except (OSError, json.JSONDecodeError):
            st = {"campaign": saved["id"]}
        return json.dumps({**st, "state": saved["want"], "floor_s_all": total})

    def _campaigns_floor_s(self) -> float:
        total = 0.0
        for path in (self.node.cfg.state_dir / "campaigns").glob("*/campaign.json"):
            with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
                total += float(json.loads(path.read_text())["floor_s"])
        return round(total, 1)

    # -- studies --------------------------------------------------------------------------
    def _default_store(self, plan_hash: str) -> Path:
        return (self.node.cfg.state_dir / "studies" / f"study-{plan_hash[:12]}.sqlite").resolve()

    async def _start_study(self, plan_json: str, store: str) -> str:
        async with self._start_lock:
            running = self._task is not None and not self._task.done()
            saved = self.state.data.get("study")
            if not plan_json.strip():
                if saved is None:
                    raise ValueError("no study to resume: give a plan")
                plan_json, store = saved["request"], store or saved["store"]
            try:
                request = await asyncio.to_thread(_parse, plan_json)
            except InputError as exc:
                raise ValueError(str(exc)) from None
            path = Path(store) if store else request.store
            path = path.resolve() if path else self._default_store(request.plan.plan_hash)
            if running:
                same = (self.job.request.plan.plan_hash == request.plan.plan_hash
                        and self.job.store == path)  # fmt: skip
                if same:
                    return json.dumps(self.job.status())
                st = self.job.status()
                raise ValueError(f"a study is running (plan {st['plan']}, {st['done']}/"
                                 f"{st['planned']}): stop it first")  # fmt: skip
            try:
                await self._launch(plan_json, path, request)
            except InputError as exc:
                raise ValueError(str(exc)) from None
            return json.dumps(self.job.status())

    async def _launch(self, plan_json: str, store: Path, request=None) -> None:
        """Check the store (refused if it holds another plan), persist the wish, run."""

        if request is None:
            request = await asyncio.to_thread(_parse, plan_json)
        job = StudyJob(request, store, on_update=self._published)
        await asyncio.to_thread(job.check_store)
        record_store(self.node.cfg.state_dir, store)
        self.state.data["study"] = {"request": plan_json, "store": str(store), "want": "running"}
        self.state.save()
        self.job = job
        await self._publish(job.status())
        self._task = self.node.spawn(self._run_job(job))

    async def _run_job(self, job) -> None:
        final = await asyncio.to_thread(job.run)
        await self._publish(final)
        study = self.state.data.get("study")
        if study is not None and final["state"] in ("finished", "failed") and self.job is job:
            study["want"] = final["state"]
            self.state.save()
        log.info("EM: study %s %s (%d/%d)%s", final["plan"], final["state"], final["done"],
                 final["planned"], f": {final['error']}" if final["error"] else "")  # fmt: skip

    def _published(self, status: dict[str, Any]) -> None:
        """From the job's thread: the status into the OPC UA variables."""
        if self._loop is not None and not self._loop.is_closed():
            asyncio.run_coroutine_threadsafe(self._publish(status), self._loop)

    async def _publish(self, status: dict[str, Any]) -> None:

        for prop, value in study_opcua_values(status).items():
            with contextlib.suppress(Exception):  # a server going down mid-update
                await self.set(prop, value)

    async def _stop_study(self) -> str:
        if self.job is None:
            raise ValueError("no study has been started")
        study = self.state.data.get("study")
        if self._task is not None and not self._task.done():
            if study is not None:
                study["want"] = "stopped"
                self.state.save()
            self.job.stop()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(asyncio.shield(self._task), STOP_WAIT_S)
        return json.dumps(self.job.status())

    async def _study_status(self) -> str:
        if self.job is not None:
            return json.dumps(self.job.status())
        study = self.state.data.get("study")  # none yet, or resuming after a restart
        return json.dumps({"state": "none" if study is None else study["want"],
                           "store": None if study is None else study["store"],
                           "plan": None, "done": None, "planned": None})  # fmt: skip

    # -- single experiments ---------------------------------------------------------------
    async def _run(self, unit: str, obj: str, face: str, conveyor: str, theta_deg: int,
                   seed: int) -> str:  # fmt: skip
        from transfertwin.cps.roles._module import MirroredUnitHAL, load_scene
        from transfertwin.study.experiment import ExperimentSpec, run_experiment, system_for

        desc = self.node.descriptors.get(unit)
        if desc is not None and desc.kind is AssetKind.PHYSICAL and \
                desc.role_class == "transfer_unit":  # E^P on the plant's unit
            return await self._run_physical(unit, obj, face, conveyor, theta_deg, seed)
        if unit not in self.node.floor.units:
            raise ValueError(f"no transfer unit {unit!r}")
        scene = load_scene()
        spec = ExperimentSpec(obj, face, conveyor, int(theta_deg), scene=scene, seed=int(seed))
        await self.set("State", "running")
        try:
            session = await self.node.peers.session(unit)
            loop = asyncio.get_running_loop()
            system = system_for(obj, "m", scene)
            hal = MirroredUnitHAL(OpcUaUnitHAL(session, loop, timeout_s=30), system.tu, loop)
            result = await asyncio.to_thread(run_experiment, spec, tu_hal=hal)
        finally:
            await self.set("State", "idle")
        await self.set("ExperimentsDone", int(await self.get("ExperimentsDone")) + 1)
        return json.dumps(result.row())

    async def _run_physical(self, unit: str, obj: str, face: str, conveyor: str,
                            theta_deg: int, seed: int) -> str:  # fmt: skip
        """E^P: the physical unit's ``RunTransfer`` over OPC UA; its log row appended to the
        floor's ``plant_experiments.csv`` and answered in the shape of an E^V record."""
        if isinstance(seed, bool) or int(seed) < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        row = await self._cycle(unit, obj, face, conveyor, theta_deg)
        return json.dumps(physical_record(row, int(seed)))

    async def _cycle(self, unit: str, obj: str, face: str, conveyor: str,
                     theta_deg: int) -> dict[str, Any]:  # fmt: skip
        """One E^P: the physical unit's ``RunTransfer``; its log row (appended to the
        floor's ``plant_experiments.csv``)."""
        if self.node.endpoint_of(unit) is None:  # joined since the last gossip: ask the graph
            await self.node.graph_status()
        await self.set("State", "running")
        try:
            async with self.node.open_session(unit, 120.0) as session:  # a cycle takes long
                row = json.loads(await session.call("RunTransfer", obj, face, conveyor,
                                                    int(theta_deg)))  # fmt: skip
        finally:
            await self.set("State", "idle")
        append_plant_log(self.node.cfg.floor_file.parent / PLANT_LOG, row)
        log.info("EM: E^P %s on %s: %s %s %s %d: success %s", row["experiment_id"], unit,
                 obj, face, conveyor, int(theta_deg), row["success"])  # fmt: skip
        await self.set("ExperimentsDone", int(await self.get("ExperimentsDone")) + 1)
        return row


def _parse(plan_json: str):  # -> StudyRequest

    return StudyRequest.parse(plan_json)
