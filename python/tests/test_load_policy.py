"""Exported players play in Python as in Rust: the Rust evaluation of a
checkpoint (`ckpt:FOLDER`, greedy) and the PyTorch actor `load_policy`
builds from the same folder play the same episodes, step for step; bad
folders are refused with the file and the reason."""

import csv
import json
import shutil
import subprocess
from pathlib import Path

import pytest

import t2e

torch = pytest.importorskip("torch")

ROOT = Path(__file__).resolve().parents[2]
STORED = ROOT / "tests" / "fixtures" / "stored"


def rust_episodes(tmp_path, captors, target, k):
    out = tmp_path / "eval"
    subprocess.run(
        [str(ROOT / "target" / "release" / "t2e-league"), "eval", "--captors", captors, "--target", target,
         "--maps", "shipped", "--k", str(k), "--speed-ratio", "1.0", "--episodes", "3", "--seed", "4",
         "--out", str(out)],
        check=True, capture_output=True, cwd=ROOT,
    )
    return [row for path in sorted(out.rglob("episodes.csv")) for row in csv.DictReader(open(path))]


def as_training_checkpoint(folder):
    """An export made into a training run's checkpoint folder: no manifest
    and none of an export's own files, so meta.json's fields are checked
    alone (its hashes cover the weights)."""
    for name in ("SHA256SUMS", "player.json", "league-config.toml", "ratings.csv"):
        (folder / name).unlink()


@pytest.mark.parametrize("side, folder", [("captors", "export-captors"), ("target", "export-target")])
def test_an_exported_player_plays_the_rust_controllers_episodes(tmp_path, side, folder):
    player = STORED / folder
    policy = t2e.load_policy(player)
    assert policy.side == side
    k = policy.num_captors
    captors, target = ("ckpt:" + str(player), "heuristic") if side == "captors" else ("heuristic", "ckpt:" + str(player))
    rows = rust_episodes(tmp_path, captors, target, k)
    assert len(rows) == 3
    env = t2e.parallel_env(maps="shipped", num_captors=k, episode_length=500, asz_info=False)
    other = t2e.ScriptedPolicy("heuristic", "target" if side == "captors" else "captors")
    for row in rows:
        observations, _ = env.reset(seed=int(row["seed"]))
        steps, captured = 0, False
        while env.agents:
            actions = {**policy(observations, env), **other(env)}
            observations, _, _, _, infos = env.step(actions)
            steps += 1
            captured = infos["target"]["captured"]
        assert (steps, captured) == (int(row["steps"]), row["captured"] == "true"), row


def test_a_corrupted_or_mismatched_folder_is_refused_with_the_file_and_the_reason(tmp_path):
    good = STORED / "export-captors"

    def copy(name, manifest=True):
        d = tmp_path / name
        shutil.copytree(good, d)
        if not manifest:
            as_training_checkpoint(d)
        return d

    changed = copy("changed")
    data = bytearray((changed / "actor.safetensors").read_bytes())
    data[-1] ^= 0x01
    (changed / "actor.safetensors").write_bytes(bytes(data))
    with pytest.raises(t2e.torch_policy.PolicyError, match="actor.safetensors.*SHA-256"):
        t2e.load_policy(changed)

    no_meta = copy("no-meta")
    (no_meta / "meta.json").unlink()
    with pytest.raises(t2e.torch_policy.PolicyError, match="meta.json.*missing"):
        t2e.load_policy(no_meta)

    future = copy("future", manifest=False)
    meta = json.loads((future / "meta.json").read_text())
    meta["format"] = 99
    (future / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(t2e.torch_policy.PolicyError, match="format 99"):
        t2e.load_policy(future)

    wider = copy("wider", manifest=False)
    meta = json.loads((wider / "meta.json").read_text())
    meta["net"]["hidden"] = 16
    (wider / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(t2e.torch_policy.PolicyError, match="actor.safetensors.*shape"):
        t2e.load_policy(wider)

    # Trained with 2 captors, shown 3: the vectors do not fit.
    policy = t2e.load_policy(good)
    env = t2e.parallel_env(maps="shipped", num_captors=3)
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="2 captors"):
        policy(observations, env)


def test_an_export_is_checked_against_its_sha256sums_before_meta_json_is_believed(tmp_path):
    good = STORED / "export-target"
    relabelled = tmp_path / "relabelled"
    shutil.copytree(good, relabelled)
    meta = json.loads((relabelled / "meta.json").read_text())
    assert meta["side"] == "target"
    meta["side"] = "captors"
    (relabelled / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(t2e.torch_policy.PolicyError, match="meta.json.*SHA256SUMS"):
        t2e.load_policy(relabelled)


@pytest.mark.parametrize(
    "edit, says",
    [
        (lambda m: m["net"].update(hidden=40000), "hidden"),
        (lambda m: m["net"].update(conv_channels=[8]), "conv_channels"),
        (lambda m: m["net"].update(patch_pool=8), "patch_pool"),
        (lambda m: m["net"].update(patch_pool=0), "patch_pool"),
        (lambda m: m["net"].update(heuristic_prior=float("nan")), "NaN"),
        (lambda m: m["net"].update(heuristic_prior=25.0), "heuristic_prior"),
        (lambda m: m.update(num_captors=0), "num_captors"),
        (lambda m: m.update(num_captors="3"), "num_captors"),
        (lambda m: m.pop("num_captors"), "num_captors"),
        (lambda m: m.update(net=[]), "net"),
        (lambda m: m.update(files=[]), "files"),
        (lambda m: m["files"].update({"../x": "0" * 64}), "files"),
    ],
)
def test_meta_json_values_are_bounded_and_refused_as_policy_errors(tmp_path, edit, says):
    folder = tmp_path / "edited"
    shutil.copytree(STORED / "export-target", folder)
    as_training_checkpoint(folder)
    meta = json.loads((folder / "meta.json").read_text())
    edit(meta)
    (folder / "meta.json").write_text(json.dumps(meta))
    with pytest.raises(t2e.torch_policy.PolicyError, match=says):
        t2e.load_policy(folder)


def test_a_missing_folder_or_a_file_is_a_policy_error(tmp_path):
    with pytest.raises(t2e.torch_policy.PolicyError, match="not a folder"):
        t2e.load_policy(tmp_path / "nowhere")
    file = tmp_path / "file"
    file.write_text("x")
    with pytest.raises(t2e.torch_policy.PolicyError, match="not a folder"):
        t2e.load_policy(file)


def test_an_export_without_its_manifest_or_with_a_folder_for_it_is_refused(tmp_path):
    gone = tmp_path / "gone"
    shutil.copytree(STORED / "export-target", gone)
    (gone / "SHA256SUMS").unlink()
    with pytest.raises(t2e.torch_policy.PolicyError, match="SHA256SUMS.*missing.*export"):
        t2e.load_policy(gone)
    folder = tmp_path / "folder"
    shutil.copytree(STORED / "export-target", folder)
    (folder / "SHA256SUMS").unlink()
    (folder / "SHA256SUMS").mkdir()
    with pytest.raises(t2e.torch_policy.PolicyError, match="SHA256SUMS.*not a file"):
        t2e.load_policy(folder)
    nan = tmp_path / "nan"
    shutil.copytree(STORED / "export-target", nan)
    as_training_checkpoint(nan)
    meta = (nan / "meta.json").read_text()
    (nan / "meta.json").write_text(meta.replace('"speed_ratio": 1.0', '"speed_ratio": NaN', 1))
    with pytest.raises(t2e.torch_policy.PolicyError, match="NaN"):
        t2e.load_policy(nan)
