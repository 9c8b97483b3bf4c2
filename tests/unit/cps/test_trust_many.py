"""`trust_certificates`: every certificate on every trust list of a floor, each written once
and hard-linked into the other folders (docs/scaling.md: a 200-asset floor's 40,000 trust
files were each written with an fsync), the lists still one per folder."""

from __future__ import annotations

import asyncio
import os

import pytest

from transfertwin.cps.opcua import TrustList, ensure_certificate, trust_certificates


@pytest.fixture(scope="module")
def certs(tmp_path_factory):
    base = tmp_path_factory.mktemp("certs")
    return [asyncio.run(ensure_certificate(base, name))[0] for name in ("client-a", "client-b")]


def test_every_list_trusts_every_certificate_through_links_of_one_copy(tmp_path, certs):
    folders = [tmp_path / f"asset{i}" / "trusted" for i in range(3)]
    trust_certificates([folders[1]], certs[:1])  # one list already holds one of them
    assert trust_certificates(folders, certs) == 5  # 6 places, one held already
    names = {f: sorted(os.listdir(f)) for f in folders}
    assert len(set(map(tuple, names.values()))) == 1 and len(names[folders[0]]) == 2
    for cert in certs:
        der = cert.read_bytes()
        assert all(TrustList(f).is_trusted(der) for f in folders)
    # one copy of each certificate: the first folder's file, linked into the others
    linked = (folders[2] / names[folders[2]][1]).stat()
    assert linked.st_ino == (folders[0] / names[folders[0]][1]).stat().st_ino
    assert linked.st_nlink == 3
    # still one list per folder: removed from one asset's, trusted by the others only
    revoked = certs[1].read_bytes()
    next(p for p in folders[2].iterdir() if "client-b" in p.name).unlink()
    assert not TrustList(folders[2]).is_trusted(revoked)
    assert TrustList(folders[0]).is_trusted(revoked) and TrustList(folders[1]).is_trusted(revoked)
    assert trust_certificates(folders, certs) == 1  # again: only what was removed


def test_without_hard_links_each_list_gets_a_copy(tmp_path, certs, monkeypatch):
    def no_link(src, dst):
        raise OSError(18, "Invalid cross-device link")

    monkeypatch.setattr(os, "link", no_link)
    folders = [tmp_path / "a", tmp_path / "b"]
    assert trust_certificates(folders, certs) == 4
    copy = next((tmp_path / "b").iterdir())
    assert copy.stat().st_nlink == 1
    assert all(TrustList(folders[1]).is_trusted(c.read_bytes()) for c in certs)


def test_cps_trust_for_the_whole_floor_links_one_copy_into_every_list(tmp_path, certs, capsys):
    from transfertwin.cli import main

    wd = tmp_path / "w"
    lists = [wd / "certs" / "trusted", *(wd / "assets" / a / "trusted" for a in ("KG", "TU_A"))]
    for folder in lists:
        folder.mkdir(parents=True)
    assert main(["cps", "trust", str(certs[0]), "--workdir", str(wd)]) == 0
    assert "3 trust lists" in capsys.readouterr().out
    files = [next(f.iterdir()) for f in lists]
    assert all(TrustList(f).is_trusted(certs[0].read_bytes()) for f in lists)
    assert {p.stat().st_ino for p in files} == {files[0].stat().st_ino}
