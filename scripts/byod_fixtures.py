#!/usr/bin/env python3
"""Writes tests/fixtures/byod/: the real iron swing (tests/fixtures/golf_iron_60hz.csv) as four
tools would hand it over, for the README's "Bring your own data" and the tests.

- mediapipe_iron.jsonl: JSON Lines, MediaPipe's 33 world landmarks by position, metres, +Y down,
  centred on the hips, a visibility each, time in ms;
- openpose_iron.csv: OpenPose BODY_25 names, millimetres, +Y down, frame numbers (give --rate);
- kinect_iron.json: an array of frames with Azure Kinect joint names, millimetres, +Y down;
- spreadsheet_iron.csv: canonical names as a spreadsheet exports them: centimetres, Z up, `;`
  with decimal commas, quoted header, byte-order mark, CRLF.

Landmarks the swing has no joint for (eyes, ears, nose, fingers, heels) are placed from the
head, hands and feet along the body's own axes; the rest are the swing's joint centres.
Usage: scripts/byod_fixtures.py
"""
import csv
import json
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "tests", "fixtures", "byod")


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def scale(a, k):
    return [x * k for x in a]


def unit(a):
    n = math.sqrt(sum(x * x for x in a)) or 1.0
    return [x / n for x in a]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def frames():
    """(time s, {joint: [x, y, z] or None}) per row of the iron fixture."""
    with open(os.path.join(ROOT, "tests", "fixtures", "golf_iron_60hz.csv")) as f:
        rows = list(csv.reader(f))
    names = [c[:-2] for c in rows[0][1::3]]
    for row in rows[1:]:
        joints = {}
        for k, name in enumerate(names):
            cells = row[1 + 3 * k: 4 + 3 * k]
            joints[name] = None if "" in cells else [float(c) for c in cells]
        yield float(row[0]), joints


def landmarks(j):
    """Every landmark the four tools name, from one frame's joints (metres, +Y up)."""
    lateral = unit(sub(j["left_shoulder"], j["right_shoulder"]))
    up = unit(sub(j["head"], j["pelvis"]))
    forward = cross(lateral, up)
    along = lambda a, b, k: add(j[b], scale(unit(sub(j[b], j[a])), k))
    at = dict(j)
    at.update({
        "nose": add(j["head"], scale(forward, 0.09)),
        "left_ear": add(j["head"], scale(lateral, 0.075)),
        "right_ear": add(j["head"], scale(lateral, -0.075)),
        "left_eye": add(add(j["head"], scale(forward, 0.07)), add(scale(lateral, 0.03), scale(up, 0.03))),
        "right_eye": add(add(j["head"], scale(forward, 0.07)), add(scale(lateral, -0.03), scale(up, 0.03))),
        "mouth": add(add(j["head"], scale(forward, 0.08)), scale(up, -0.04)),
        "left_hand": along("left_elbow", "left_wrist", 0.08),
        "right_hand": along("right_elbow", "right_wrist", 0.08),
        "left_heel": add(j["left_ankle"], scale(sub(j["left_ankle"], j["left_toe"]), 0.35)),
        "right_heel": add(j["right_ankle"], scale(sub(j["right_ankle"], j["right_toe"]), 0.35)),
        "neck_mid": scale(add(j["left_shoulder"], j["right_shoulder"]), 0.5),
        "hips_mid": scale(add(j["left_hip"], j["right_hip"]), 0.5),
    })
    return at


MEDIAPIPE = [  # (landmark, source)
    ("nose", "nose"), ("left_eye_inner", "left_eye"), ("left_eye", "left_eye"),
    ("left_eye_outer", "left_eye"), ("right_eye_inner", "right_eye"), ("right_eye", "right_eye"),
    ("right_eye_outer", "right_eye"), ("left_ear", "left_ear"), ("right_ear", "right_ear"),
    ("mouth_left", "mouth"), ("mouth_right", "mouth"), ("left_shoulder", "left_shoulder"),
    ("right_shoulder", "right_shoulder"), ("left_elbow", "left_elbow"), ("right_elbow", "right_elbow"),
    ("left_wrist", "left_wrist"), ("right_wrist", "right_wrist"), ("left_pinky", "left_hand"),
    ("right_pinky", "right_hand"), ("left_index", "left_hand"), ("right_index", "right_hand"),
    ("left_thumb", "left_hand"), ("right_thumb", "right_hand"), ("left_hip", "left_hip"),
    ("right_hip", "right_hip"), ("left_knee", "left_knee"), ("right_knee", "right_knee"),
    ("left_ankle", "left_ankle"), ("right_ankle", "right_ankle"), ("left_heel", "left_heel"),
    ("right_heel", "right_heel"), ("left_foot_index", "left_toe"), ("right_foot_index", "right_toe"),
]

OPENPOSE = [
    ("Nose", "nose"), ("Neck", "neck_mid"), ("RShoulder", "right_shoulder"), ("RElbow", "right_elbow"),
    ("RWrist", "right_wrist"), ("LShoulder", "left_shoulder"), ("LElbow", "left_elbow"),
    ("LWrist", "left_wrist"), ("MidHip", "hips_mid"), ("RHip", "right_hip"), ("RKnee", "right_knee"),
    ("RAnkle", "right_ankle"), ("LHip", "left_hip"), ("LKnee", "left_knee"), ("LAnkle", "left_ankle"),
    ("REye", "right_eye"), ("LEye", "left_eye"), ("REar", "right_ear"), ("LEar", "left_ear"),
    ("LBigToe", "left_toe"), ("LSmallToe", "left_toe"), ("LHeel", "left_heel"),
    ("RBigToe", "right_toe"), ("RSmallToe", "right_toe"), ("RHeel", "right_heel"),
]

KINECT = [
    ("PELVIS", "pelvis"), ("SPINE_NAVAL", "spine"), ("SPINE_CHEST", "thorax"), ("NECK", "neck"),
    ("SHOULDER_LEFT", "left_shoulder"), ("ELBOW_LEFT", "left_elbow"), ("WRIST_LEFT", "left_wrist"),
    ("HAND_LEFT", "left_hand"), ("SHOULDER_RIGHT", "right_shoulder"), ("ELBOW_RIGHT", "right_elbow"),
    ("WRIST_RIGHT", "right_wrist"), ("HAND_RIGHT", "right_hand"), ("HIP_LEFT", "left_hip"),
    ("KNEE_LEFT", "left_knee"), ("ANKLE_LEFT", "left_ankle"), ("FOOT_LEFT", "left_toe"),
    ("HIP_RIGHT", "right_hip"), ("KNEE_RIGHT", "right_knee"), ("ANKLE_RIGHT", "right_ankle"),
    ("FOOT_RIGHT", "right_toe"), ("HEAD", "head"), ("NOSE", "nose"), ("EYE_LEFT", "left_eye"),
    ("EAR_LEFT", "left_ear"), ("EYE_RIGHT", "right_eye"), ("EAR_RIGHT", "right_ear"),
]


def y_down(p, k=1.0):
    return [round(p[0] * k, 2), round(-p[1] * k, 2), round(-p[2] * k, 2)]


def main():
    os.makedirs(OUT, exist_ok=True)
    data = [(t, landmarks(j)) for t, j in frames()]

    with open(os.path.join(OUT, "mediapipe_iron.jsonl"), "w") as f:
        for t, at in data:
            centre = at["hips_mid"]
            points = []
            for _, source in MEDIAPIPE:
                x, y, z = y_down(sub(at[source], centre), 1.0)
                points.append({"x": round(x, 4), "y": round(y, 4), "z": round(z, 4), "visibility": 0.99})
            f.write(json.dumps({"timestamp_ms": round(t * 1000.0, 1), "pose_world_landmarks": points}) + "\n")

    with open(os.path.join(OUT, "openpose_iron.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame"] + [f"{n}_{a}" for n, _ in OPENPOSE for a in "xyz"])
        for k, (t, at) in enumerate(data):
            w.writerow([round(t * 60)] + [v for _, s in OPENPOSE for v in y_down(at[s], 1000.0)])

    with open(os.path.join(OUT, "kinect_iron.json"), "w") as f:
        body = [{"time": round(t, 4), "joints": {n: y_down(at[s], 1000.0) for n, s in KINECT}} for t, at in data]
        json.dump(body, f, separators=(",", ":"))

    canonical = [c for c in ("pelvis left_hip left_knee left_ankle left_toe right_hip right_knee right_ankle "
                             "right_toe spine thorax neck head head_top left_shoulder left_elbow left_wrist "
                             "right_shoulder right_elbow right_wrist").split()]
    with open(os.path.join(OUT, "spreadsheet_iron.csv"), "w", newline="", encoding="utf-8-sig") as f:
        header = ["time"] + [f"{n}_{a}" for n in canonical for a in "xyz"]
        f.write(";".join(f'"{h}"' for h in header) + "\r\n")
        for t, at in data:
            cells = [f"{t:.4f}"]
            for n in canonical:
                x, y, z = at[n]
                cells += [f"{v * 100:.2f}" for v in (x, -z, y)]  # Z up: (x, y, z) -> (x, -z, y)
            f.write(";".join(c.replace(".", ",") for c in cells) + "\r\n")


if __name__ == "__main__":
    main()
