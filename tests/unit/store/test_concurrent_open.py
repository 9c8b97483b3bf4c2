"""Opening a new store while another connection polls it (`study status` while `study run`
starts; the crash-safety test's reader): the switch to WAL waits instead of failing with
"database is locked"."""

from __future__ import annotations

import threading

from transfertwin._errors import InputError
from transfertwin.store import SQLiteResultStore


def test_opening_a_new_store_while_a_reader_polls_it_never_fails(tmp_path):
    failures = []
    for i in range(60):
        db = tmp_path / f"study{i}.sqlite"
        stop = threading.Event()

        def poll(db=db, stop=stop):
            while not stop.is_set():
                try:
                    with SQLiteResultStore(db, create=False) as reader:
                        reader.count()
                except InputError as exc:
                    if "no such result database" not in str(
                        exc
                    ) and "not a transfertwin" not in str(exc):
                        failures.append(f"reader: {exc}")

        reader = threading.Thread(target=poll)
        reader.start()
        try:
            with SQLiteResultStore(db) as store:
                store.count()
        except InputError as exc:
            failures.append(f"writer: {exc}")
        finally:
            stop.set()
            reader.join()
    assert failures == []
