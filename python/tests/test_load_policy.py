"""Exported players play in Python as in Rust: the Rust evaluation of a
checkpoint (`ckpt:FOLDER`, greedy) and the PyTorch actor `load_policy`
builds from the same folder play the same episodes, step for step; bad
folders are refused with the file and the reason."""

import csv
import hashlib
import json
import os
import shutil
import struct
import subprocess
import threading
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


def reseal(folder):
    """Writes the folder's SHA256SUMS anew, as the Rust writer does (every
    other file, sorted): an edit made on purpose then reaches the checks
    behind the manifest."""
    folder = Path(folder)
    names = sorted(p.name for p in folder.iterdir() if p.name != "SHA256SUMS" and p.is_file())
    lines = [f"{hashlib.sha256((folder / n).read_bytes()).hexdigest()}  {n}\n" for n in names]
    (folder / "SHA256SUMS").write_text("".join(lines))


def as_training_checkpoint(folder):
    """An export made into a training run's checkpoint folder: none of an
    export's own files, and the manifest training writes."""
    for name in ("player.json", "league-config.toml", "ratings.csv"):
        (folder / name).unlink()
    reseal(folder)


def edit_meta(folder, edit):
    meta = json.loads((folder / "meta.json").read_text())
    edit(meta)
    (folder / "meta.json").write_text(json.dumps(meta))
    reseal(folder)


def write_checkpoint(folder, side="captors", num_captors=3, net=None, seed=0, **fields):
    """A checkpoint folder made here, not by the Rust binary: an actor of
    random weights for `net`, its meta.json (with `fields` on top) and
    SHA256SUMS."""
    from t2e.torch_policy import _build_actor, _sight_len

    net = {**dict(hidden=8, conv_channels=[2, 4], patch_pool=4, vector_input="egocentric"), **(net or {})}
    torch.manual_seed(seed)
    actor = _build_actor(net, 5 + 5 * num_captors + _sight_len(net))
    header, blobs, offset = {}, [], 0
    for name, t in actor.state_dict().items():
        data = t.detach().contiguous().numpy().astype("<f4").tobytes()
        header[name] = {"dtype": "F32", "shape": list(t.shape), "data_offsets": [offset, offset + len(data)]}
        blobs.append(data)
        offset += len(data)
    head = json.dumps(header).encode()
    folder = Path(folder)
    folder.mkdir(parents=True)
    weights = struct.pack("<Q", len(head)) + head + b"".join(blobs)
    (folder / "actor.safetensors").write_bytes(weights)
    meta = dict(format=2, side=side, num_captors=num_captors, net=net, files={"actor.safetensors": hashlib.sha256(weights).hexdigest()})
    meta.update(fields)
    (folder / "meta.json").write_text(json.dumps(meta))
    reseal(folder)
    return folder


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
    edit_meta(future, lambda m: m.update(format=99))
    with pytest.raises(t2e.torch_policy.PolicyError, match="format 99"):
        t2e.load_policy(future)

    wider = copy("wider", manifest=False)
    edit_meta(wider, lambda m: m["net"].update(hidden=16))
    with pytest.raises(t2e.torch_policy.PolicyError, match="actor.safetensors.*shape"):
        t2e.load_policy(wider)

    # Trained with 2 captors, shown 3: the vectors do not fit.
    policy = t2e.load_policy(good)
    env = t2e.parallel_env(maps="shipped", num_captors=3)
    observations, _ = env.reset(seed=0)
    with pytest.raises(ValueError, match="trained with num_captors = 2 .*this env has num_captors = 3; make the env with num_captors=2"):
        policy(observations, env)
    with pytest.raises(ValueError, match="2 captors"):
        policy(observations)


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
        (lambda m: m["net"].update(heuristic_prior=10.0, prior_teacher="robust:10:heuristic"), "prior_teacher.*planner"),
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
    edit_meta(folder, edit)
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
    with pytest.raises(t2e.torch_policy.PolicyError, match="SHA256SUMS missing: every checkpoint folder carries a manifest"):
        t2e.load_policy(gone)
    folder = tmp_path / "folder"
    shutil.copytree(STORED / "export-target", folder)
    (folder / "SHA256SUMS").unlink()
    (folder / "SHA256SUMS").mkdir()
    with pytest.raises(t2e.torch_policy.PolicyError, match="SHA256SUMS.*not a regular file"):
        t2e.load_policy(folder)
    nan = tmp_path / "nan"
    shutil.copytree(STORED / "export-target", nan)
    as_training_checkpoint(nan)
    meta = (nan / "meta.json").read_text()
    (nan / "meta.json").write_text(meta.replace('"speed_ratio": 1.0', '"speed_ratio": NaN', 1))
    reseal(nan)
    with pytest.raises(t2e.torch_policy.PolicyError, match="NaN"):
        t2e.load_policy(nan)


def test_every_checkpoint_folder_needs_its_manifest_training_ones_too(tmp_path):
    run = tmp_path / "run"
    shutil.copytree(STORED / "train-run", run)
    checkpoint = run / "checkpoints" / "captors-000000000160"
    assert not (checkpoint / "SHA256SUMS").exists()  # written before manifests
    with pytest.raises(t2e.torch_policy.PolicyError, match=f"{checkpoint}.*SHA256SUMS missing.*re-export it or retrain"):
        t2e.load_policy(checkpoint)
    reseal(checkpoint)
    assert t2e.load_policy(checkpoint).num_captors == 3


def test_player_json_and_meta_json_name_the_same_side(tmp_path):
    folder = tmp_path / "relabelled"
    shutil.copytree(STORED / "export-target", folder)
    edit_meta(folder, lambda m: m.update(side="captors"))
    with pytest.raises(t2e.torch_policy.PolicyError, match=r"player.json: side 'target', but .*meta.json says 'captors'"):
        t2e.load_policy(folder)


def test_a_fifo_listed_in_the_manifest_is_not_a_regular_file_and_never_opened(tmp_path):
    folder = tmp_path / "fifo"
    shutil.copytree(STORED / "export-target", folder)
    (folder / "ratings.csv").unlink()
    os.mkfifo(folder / "ratings.csv")
    caught = []

    def load():
        try:
            t2e.load_policy(folder)
        except t2e.torch_policy.PolicyError as e:
            caught.append(str(e))

    # Opening the FIFO would block for ever: in a thread, a hang fails here.
    worker = threading.Thread(target=load, daemon=True)
    worker.start()
    worker.join(60)
    assert not worker.is_alive(), "load_policy opened the FIFO"
    assert len(caught) == 1 and "ratings.csv: not a regular file, though SHA256SUMS lists it" in caught[0]


def test_wall_rays_need_the_fixed_range_they_were_trained_at(tmp_path):
    sight = dict(sight=dict(wall_rays=8))
    old = write_checkpoint(tmp_path / "old", "target", 2, sight)
    with pytest.raises(t2e.torch_policy.PolicyError, match="net.sight.wall_rays = 8, but no wall_ray_range_m: .*fixed 16 m; retrain it"):
        t2e.load_policy(old)
    other = write_checkpoint(tmp_path / "other", "target", 2, sight, wall_ray_range_m=12.5)
    with pytest.raises(t2e.torch_policy.PolicyError, match="wall_ray_range_m = 12.5"):
        t2e.load_policy(other)
    good = write_checkpoint(tmp_path / "good", "target", 2, sight, wall_ray_range_m=16.0)
    policy = t2e.load_policy(good)
    env = t2e.parallel_env(maps="shipped", num_captors=2, wall_rays=8)
    observations, _ = env.reset(seed=0)
    assert set(policy(observations, env)) == {"target"}
    # Without rays the field is not needed.
    assert t2e.load_policy(write_checkpoint(tmp_path / "plain", "target", 2)).wall_rays == 0


def test_a_run_folder_plays_the_checkpoint_ckpt_would(tmp_path):
    run = tmp_path / "run"
    shutil.copytree(STORED / "train-run", run)
    for checkpoint in (run / "checkpoints").iterdir():
        reseal(checkpoint)
    # state.json names the newest; the one it names is played, as `ckpt:` plays it.
    assert t2e.load_policy(run).folder == run / "checkpoints" / "captors-000000000160"
    state = json.loads((run / "state.json").read_text())
    state["checkpoints"] = [["captors", "captors-000000000080"]]
    (run / "state.json").write_text(json.dumps(state))
    assert t2e.load_policy(run).folder.name == "captors-000000000080"
    assert t2e.load_policy(run / "checkpoints").folder.name == "captors-000000000160"
    env = t2e.parallel_env(maps="shipped", captors=f"ckpt:{run}", episode_length=5)
    assert env._kwargs["captors"] == f"ckpt:{run / 'checkpoints' / 'captors-000000000080'}"
    with pytest.raises(t2e.torch_policy.PolicyError, match="no target checkpoint"):
        t2e.load_policy(run, side="target")
