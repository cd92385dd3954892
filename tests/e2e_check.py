#!/usr/bin/env python3
"""Helper of cli_check_e2e.sh (standard library only).

  e2e_check.py script DEMO TMP       writes TMP/check.script: the planner's
                                     taps, from the demo's ground truth
  e2e_check.py check DEMO TMP MR     checks what the view and the exports
                                     wrote; prints "ok N", "info: ..." and
                                     one line per failure
"""
import json
import math
import os
import struct
import subprocess
import sys
import zipfile
import zlib

# ---------------------------------------------------------------- geometry


def glb_json(path):
    b = open(path, "rb").read()
    return json.loads(b[20:20 + struct.unpack_from("<I", b, 12)[0]])


def node_box(g, name):
    """World bounds of a root node with a translation-only matrix and a mesh."""
    nodes = g["nodes"]
    i = [k for k, n in enumerate(nodes) if n.get("name") == name][0]
    n = nodes[i]
    assert not any(i in m.get("children", []) for m in nodes), name + " is not a root node"
    m = n.get("matrix", [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0] + n.get("translation", [0, 0, 0]) + [1])
    assert m[0] == 1 and m[5] == 1 and m[10] == 1, name + " is rotated or scaled"
    acc = g["accessors"][g["meshes"][n["mesh"]]["primitives"][0]["attributes"]["POSITION"]]
    t = m[12:15]
    return [t[k] + acc["min"][k] for k in range(3)], [t[k] + acc["max"][k] for k in range(3)]


def project(cam, w_from_c, X, distort=False):
    """Pixel (OpenCV convention) of world point X; None behind the camera."""
    m = w_from_c
    t = [m[3], m[7], m[11]]
    q = [sum(m[4 * r + c] * (X[r] - t[r]) for r in range(3)) for c in range(3)]
    if q[2] <= 1e-9:
        return None
    x, y = q[0] / q[2], q[1] / q[2]
    if distort:
        k1, k2, p1, p2, k3 = (list(cam.get("dist", [])) + [0] * 5)[:5]
        r2 = x * x + y * y
        rad = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2
        x, y = (x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x), y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)
    return cam["fx"] * x + cam["cx"], cam["fy"] * y + cam["cy"]


# --------------------------------------------------------------------- PNG


def png_read(path):
    """(width, height, channels, bytes) of an 8-bit non-interlaced PNG."""
    b = open(path, "rb").read()
    assert b[:8] == b"\x89PNG\r\n\x1a\n", path + " is not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(b):
        n, kind = struct.unpack_from(">I4s", b, pos)
        data = b[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, lace = struct.unpack(">IIBBBBB", data)
            assert depth == 8 and lace == 0, path + ": not an 8-bit non-interlaced PNG"
            ch = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
        elif kind == b"IDAT":
            idat += data
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * ch
    out = bytearray(stride * h)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            c = prev[i - ch] if i >= ch else 0
            bb = prev[i]
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + bb) & 255
            elif f == 3:
                line[i] = (line[i] + (a + bb) // 2) & 255
            elif f == 4:
                p = a + bb - c
                pa, pb, pc = abs(p - a), abs(p - bb), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else bb if pb <= pc else c)) & 255
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return w, h, ch, bytes(out)


def magenta_centroid(img):
    """Centre of the pin's pure magenta disc, and its pixel count."""
    w, h, ch, px = img
    sx = sy = n = 0
    for y in range(h):
        row = y * w * ch
        for x in range(w):
            i = row + x * ch
            if px[i] >= 250 and px[i + 1] <= 5 and px[i + 2] >= 250:
                sx += x
                sy += y
                n += 1
    return (sx / n, sy / n, n) if n else (None, None, 0)


# ------------------------------------------------------------------ script


def frames_seeing(d, X, margin=(0.05, 0.2, 0.95, 0.9), last=40):
    """(frame, (u, v) fractions of the picture) where X is seen, the pose good."""
    cam = json.load(open(d + "/recording/meta.json"))["camera"]
    gt = [json.loads(l) for l in open(d + "/recording/groundtruth.jsonl") if l.strip()]
    # Frames whose tracked pose is good (within 15 mm of the truth), as a
    # planner picks frames where the overlay sits well.
    good = set()
    truth = {g["frame"]: g["world_from_camera"] for g in gt}
    for l in open(d + "/recording/frames.jsonl"):
        if not l.strip():
            continue
        r = json.loads(l)
        p, t = r["pose"], truth.get(r["frame"])
        if p["valid"] and t and math.dist([p["world_from_camera"][i] for i in (3, 7, 11)], [t[i] for i in (3, 7, 11)]) < 0.015:
            good.add(r["frame"])
    out = []
    for g in gt:
        if g["frame"] not in good or g["frame"] >= last:
            continue
        p = project(cam, g["world_from_camera"], X)
        if not p:
            continue
        u, v = (p[0] + 0.5) / cam["width"], (p[1] + 0.5) / cam["height"]
        if margin[0] < u < margin[2] and margin[1] < v < margin[3]:
            out.append((g["frame"], (u, v)))
    return out


def spread(frames, n):
    """Up to n of frames, spread evenly, the first and the last among them."""
    if len(frames) <= n:
        return frames
    return [frames[round(i * (len(frames) - 1) / (n - 1))] for i in range(n)]


def plan(d):
    """The three findings: the moved machine's edge seen in several frames,
    the machine marked where the camera points at it, and an unchanged
    column's corner edge seen in several frames (the corner seen from
    nearest, on average)."""
    planned, built = glb_json(d + "/hall_planned.glb"), glb_json(d + "/hall_built.glb")
    gt = {json.loads(l)["frame"]: json.loads(l)["world_from_camera"] for l in open(d + "/recording/groundtruth.jsonl") if l.strip()}
    cam_at = lambda f: [gt[f][3], gt[f][7], gt[f][11]]
    best = None
    for node in built["nodes"]:
        name = node.get("name", "")
        if not name.startswith("Column_") or name == "Column_1_0":  # Column_1_0 was not built
            continue
        try:
            lo, hi = node_box(built, name)
            node_box(planned, name)
        except (IndexError, KeyError, AssertionError):
            continue
        for c in ([hi[0], 1.5, hi[2]], [lo[0], 1.5, hi[2]], [hi[0], 1.5, lo[2]], [lo[0], 1.5, lo[2]]):
            s = frames_seeing(d, c, margin=(0.15, 0.25, 0.85, 0.85))
            if len(s) < 3:
                continue
            q = sum(math.dist(c, cam_at(f)) for f, _ in s) / len(s) / math.sqrt(len(s))
            if best is None or q < best[0]:
                best = (q, name, c, s)
    assert best, "no column is seen from three frames"
    _, col, corner, col_seen = best
    lo, hi = node_box(planned, "Machine_2")
    machine_centre = [(lo[k] + hi[k]) / 2 for k in range(3)]
    blo, bhi = node_box(built, "Machine_2")
    edge = [bhi[0], 1.5, bhi[2]]  # the built machine's +x,+z vertical edge
    edge_seen = frames_seeing(d, edge)
    seen = dict(frames_seeing(d, machine_centre))
    assert len(edge_seen) >= 2 and seen, "the machine is not seen"
    mf = min(seen, key=lambda f: math.hypot(seen[f][0] - 0.5, seen[f][1] - 0.5))  # pointed at it
    return machine_centre, (mf, seen[mf]), edge, spread(edge_seen, 4), col, corner, spread(col_seen, 6)


def write_script(d, tmp):
    machine_centre, mark, edge, edge_taps, col, corner, col_taps = plan(d)
    lines, t = [], 0.3

    def add(dt, cmd):
        nonlocal t
        t += dt
        lines.append("%.2f %s" % (t, cmd))

    def measure(taps, category):
        add(0.5, "tap @measure")
        for f, uv in taps:
            add(0.3, "seek %d" % f)
            add(0.5, "tap @picture %.5f %.5f" % uv)
        add(0.5, "tap @measure")
        add(1.0, "state %s/s_measured_%d.json" % (tmp, taps[0][0]))
        add(0.3, "tap @note%d" % category)

    # The moved machine's edge, measured (3: moved).
    measure(edge_taps, 3)
    # The machine marked where the plan shows it, with a typed note.
    add(1.0, "seek %d" % mark[0])
    add(0.5, "tap @mark")
    add(0.4, "tap @picture %.5f %.5f" % mark[1])
    add(0.8, "state %s/s_chooser.json" % tmp)
    add(0.3, "tap @note_text")
    add(0.3, "text stands too far to the right @planner #layout !high")
    add(0.5, "key enter")
    add(0.3, "tap @note3")
    add(1.0, "state %s/s_marked.json" % tmp)
    # An unchanged column's edge, measured (6: other).
    measure(col_taps, 6)
    add(1.0, "state %s/s_end.json" % tmp)
    add(0.3, "shot %s/view_end.png" % tmp)
    add(0.5, "quit")
    open(tmp + "/check.script", "w").write("\n".join(lines) + "\n")
    json.dump({"machine_centre": machine_centre, "edge": edge, "column": col, "column_point": corner},
              open(tmp + "/plan.json", "w"))
    print("plan: Machine_2's edge from frames %s; the machine marked at frame %d; %s's edge from frames %s"
          % ([f for f, _ in edge_taps], mark[0], col, [f for f, _ in col_taps]))


# ------------------------------------------------------------------- check


class Checks:
    def __init__(self):
        self.passed = 0

    def __call__(self, cond, msg):
        if cond:
            self.passed += 1
        else:
            print(msg)
        return cond


def newest(lines):
    """The newest line of each mark, in the order of their first lines."""
    order, by = [], {}
    for l in lines:
        k = l.get("id") or json.dumps(l)
        if k not in by:
            order.append(k)
        by[k] = l
    return [by[k] for k in order]


def check(d, tmp, mr):
    ok = Checks()
    ann = tmp + "/session/annotations.jsonl"
    if not ok(os.path.exists(ann), "no annotations.jsonl: the view saved no marks"):
        print("ok %d" % ok.passed)
        return
    marks = newest([json.loads(l) for l in open(ann) if l.strip()])
    ok(len(marks) == 3, "want 3 marks (the machine, its measured edge, the column), got %d" % len(marks))
    if len(marks) < 1:
        print("ok %d" % ok.passed)
        return
    # Which is which: the plain mark, the machine's and the column's measurements.
    plain = [m for m in marks if "measured_point" not in m]
    meas = [m for m in marks if "measured_point" in m]
    m1 = plain[0] if plain else marks[0]
    # The mark's part and what the planner typed.
    ok(m1.get("node") == "Machine_2", "the mark is on %r, want Machine_2" % m1.get("node"))
    ok(m1.get("category") == "moved", "the mark's category is %r, want moved" % m1.get("category"))
    ok(m1.get("note") == "stands too far to the right", "the typed note is %r" % m1.get("note"))
    ok(m1.get("assignee") == "planner" and m1.get("labels") == ["layout"] and m1.get("priority") == "high",
       "the note's fields: assignee %r labels %r priority %r" % (m1.get("assignee"), m1.get("labels"), m1.get("priority")))
    ok(m1.get("title") == "Moved: Machine_2", "the mark's title is %r" % m1.get("title"))
    # The pin in both snapshot pictures, within 2 px of the marked point.
    snap = m1.get("snapshot", {})
    sj = json.load(open(tmp + "/session/" + snap["pose"])) if snap.get("pose") else None
    if ok(sj and m1.get("world"), "the mark has no snapshot pose or no world point"):
        cam, pose, X = sj["camera"], sj["pose"]["world_from_camera"], m1["world"]
        fr = png_read(tmp + "/session/" + snap["frame"])
        s = fr[0] / cam["width"]
        c = dict(cam, fx=cam["fx"] * s, fy=cam["fy"] * s, cx=(cam["cx"] + 0.5) * s - 0.5, cy=(cam["cy"] + 0.5) * s - 0.5)
        want = project(c, pose, X, distort=True)
        cx, cy, n = magenta_centroid(fr)
        ok(n > 10 and want and math.hypot(cx - want[0], cy - want[1]) <= 2.0,
           "the camera picture's pin is at %s (%d px), the marked point projects to %s" % ((cx, cy), n, want))
        sc = png_read(tmp + "/session/" + snap["screen"])
        s2 = sc[0] / cam["width"]
        c2 = dict(cam, fx=cam["fx"] * s2, fy=cam["fy"] * sc[1] / cam["height"], cx=(cam["cx"] + 0.5) * s2 - 0.5,
                  cy=(cam["cy"] + 0.5) * sc[1] / cam["height"] - 0.5)
        want2 = project(c2, pose, X)
        sx, sy, n2 = magenta_centroid(sc)
        ok(n2 > 10 and want2 and math.hypot(sx - want2[0], sy - want2[1]) <= 2.0,
           "the overlay's pin is at %s (%d px), the marked point projects to %s" % ((sx, sy), n2, want2))
        print("info: pin offsets: camera picture %.2f px, overlay %.2f px"
              % (math.hypot(cx - want[0], cy - want[1]) if n else -1, math.hypot(sx - want2[0], sy - want2[1]) if n2 else -1))
        # No UI in the overlay snapshot: the picture as rendered (not the
        # 800x600 window), and it matches a headless render of the same
        # view (same frame, same transparency) but for the pin.
        ok(abs(sc[0] / sc[1] - cam["width"] / cam["height"]) < 0.01 and (sc[0], sc[1]) != (800, 600),
           "the overlay snapshot is %dx%d: the window, not the picture" % (sc[0], sc[1]))
        view = {"camera": cam, "world_from_camera": pose}
        json.dump(view, open(tmp + "/snap_view.json", "w"))
        frame_png = "%s/recording/frames/%06d.png" % (d, m1["frame_index"])
        if not os.path.exists(frame_png):
            frame_png = frame_png[:-3] + "jpg"
        r = subprocess.run([mr, "render", "--scene", d + "/scene_planned.json", "--view", tmp + "/snap_view.json",
                            "--out", tmp + "/snap_render.png", "--size", "%dx%d" % (sc[0], sc[1]), "--video", frame_png,
                            "--alpha", str(sj.get("alpha", 0.5))], capture_output=True, text=True)
        if ok(r.returncode == 0, "render of the snapshot's view: " + r.stderr.strip()):
            rr = png_read(tmp + "/snap_render.png")
            w, h, ch, a = sc
            b = rr[3]
            big = total = 0
            for y in range(h):
                for x in range(w):
                    if math.hypot(x - want2[0], y - want2[1]) <= 9:
                        continue
                    i, j = (y * w + x) * ch, (y * w + x) * rr[2]
                    total += 1
                    if max(abs(a[i + k] - b[j + k]) for k in range(3)) > 48:
                        big += 1
            ok(big <= 0.002 * total, "the overlay snapshot differs from the rendered picture in %d of %d pixels (UI on it?)"
               % (big, total))
    # The measured marks: the machine 0.30 m off, the column in place.
    if len(meas) == 2:
        m2, m3 = meas
        d2, s2 = m2.get("measured_distance_m"), m2.get("measured_sigma_m")
        ok(m2.get("measured_planned_node", "").startswith("Machine_2") and d2 is not None and s2 is not None
           and abs(d2 - 0.30) <= max(2 * s2, 0.02),
           "the machine's edge measured %r m +- %r to %r (want 0.30 m)" % (d2, s2, m2.get("measured_planned_node")))
        ok("along +x" in m2.get("title", ""), "the measured mark's title %r does not say the direction" % m2.get("title"))
        d3, s3 = m3.get("measured_distance_m"), m3.get("measured_sigma_m")
        ok(d3 is not None and d3 <= max(2 * s3, 0.02), "the unchanged column measured %r m +- %r" % (d3, s3))
        print("info: measured: machine %.3f m +- %.3f, column %.3f m +- %.3f" % (d2 or -1, s2 or -1, d3 or -1, s3 or -1))
        # The verdicts: the moved machine out of tolerance, the unchanged
        # column within, each with its 95 % interval (k = 2) and the
        # tolerance used, and in the mark's title.
        v2, v3 = m2.get("verdict") or {}, m3.get("verdict") or {}
        for v, d_, s_ in ((v2, d2, s2), (v3, d3, s3)):
            ok(v and v.get("k") == 2 and abs(v["interval_mm"][1] - (d_ + 2 * s_) * 1000) < 1e-6
               and abs(v["sigma_mm"] - s_ * 1000) < 1e-9, "a measured mark's verdict lacks its interval or k: %r" % v)
        # The hall's table for the machines; DIN 18202 by nominal size for the column.
        ok(v2.get("tolerance") == "hall table, part Machine_*" and v2.get("limit_mm") == 10,
           "the machine was not judged by the hall's table: %r" % v2)
        ok(v3.get("tolerance", "").startswith("DIN 18202 Table 1, "), "the column was not judged by DIN 18202: %r" % v3)
        ok(v2.get("verdict") == "out", "the moved machine's verdict is %r, want out: %r" % (v2.get("verdict"), v2))
        ok(v3.get("verdict") == "within", "the unchanged column's verdict is %r, want within: %r" % (v3.get("verdict"), v3))
        ok(m2.get("title", "").endswith(", out of tolerance") and m3.get("title", "").endswith(", within tolerance"),
           "the measured marks' titles lack the verdict: %r, %r" % (m2.get("title"), m3.get("title")))
        print("info: verdicts: machine %s (%s), column %s (%s)" % (v2.get("verdict"), v2.get("tolerance"),
                                                                 v3.get("verdict"), v3.get("tolerance")))
        # The registration's uncertainty is in the interval: every tap of
        # each measurement carried its frame's pose covariance.
        for f in ("s_measured_%d.json" % m2["measured_frames"][0], "s_measured_%d.json" % m3["measured_frames"][0]):
            st = json.load(open(tmp + "/" + f)) if os.path.exists(tmp + "/" + f) else {}
            me = st.get("measure") or {}
            ok(me.get("taps", 0) >= 2 and me.get("taps_with_pose_covariance") == me.get("taps"),
               "%s: %r of %r taps carried the pose covariance" % (f, me.get("taps_with_pose_covariance"), me.get("taps")))
            ok((me.get("verdict") or {}).get("verdict") in ("within", "out", "undecided"),
               "%s: the view showed no verdict" % f)
        st = json.load(open(tmp + "/s_end.json")) if os.path.exists(tmp + "/s_end.json") else {}
        pv = [p.get("verdict") for p in st.get("pins", [])]
        ok(sorted(pv) == ["", "out", "within"], "the pins' verdicts are %r" % pv)
    # The exports.
    for path, v3 in ((tmp + "/findings.bcf", False), (tmp + "/findings-3.0.bcf", True)):
        if not ok(os.path.exists(path), "no " + path):
            continue
        z = zipfile.ZipFile(path)
        mk = [z.read(n).decode() for n in z.namelist() if n.endswith("markup.bcf")]
        ok(len(mk) == len(marks), "%s: %d topics for %d marks" % (path, len(mk), len(marks)))
        t1 = [x for x in mk if "<Title>Moved: Machine_2</Title>" in x]
        ok(len(t1) == 1, "%s: no topic titled 'Moved: Machine_2'" % path)
        if t1:
            x = t1[0]
            ok('TopicType="Moved"' in x and "<AssignedTo>planner</AssignedTo>" in x and "<Priority>high</Priority>" in x
               and ("<Label>layout</Label>" if v3 else "<Labels>layout</Labels>") in x,
               "%s: the topic's type, assignee, priority or label is missing" % path)
        # The measured findings: the verdict in the title, the description
        # (with the interval and the tolerance) and the labels.
        lab = "<Label>%s</Label>" if v3 else "<Labels>%s</Labels>"
        tv = [x for x in mk if ", out of tolerance</Title>" in x]
        ok(len(tv) == 1 and "Verdict: out of tolerance: " in tv[0] and "95 % interval" in tv[0]
           and lab % "out of tolerance" in tv[0], "%s: no topic of the machine's verdict (title, description, label)" % path)
        tw = [x for x in mk if ", within tolerance</Title>" in x]
        ok(len(tw) == 1 and "Verdict: within tolerance: " in tw[0] and lab % "within tolerance" in tw[0],
           "%s: no topic of the column's verdict" % path)
        if v3:
            ext = z.read("extensions.xml").decode()
            ok("<TopicType>Moved</TopicType>" in ext and "<User>planner</User>" in ext and "<TopicLabel>layout</TopicLabel>" in ext,
               "3.0 extensions.xml does not declare the values used")
    html = open(tmp + "/report/index.html").read() if os.path.exists(tmp + "/report/index.html") else ""
    ok("Moved: Machine_2" in html and "img/mark_1_overlay.png" in html and "magenta pin" in html,
       "the report lacks the mark's title or its pictures")
    ok("Distances in metres" not in html and "camera to the point" in html,
       "the report's units or the words for its distances")
    ok("<th>verdict</th>" in html and html.count(">out of tolerance (95 %: ") == 1
       and html.count(">within tolerance (95 %: ") == 1 and "Verdict: out of tolerance: " in html
       and "straddles the limit" in html, "the report lacks the verdict column or its words")
    print("ok %d" % ok.passed)


if __name__ == "__main__":
    if sys.argv[1] == "script":
        write_script(sys.argv[2], sys.argv[3])
    else:
        check(sys.argv[2], sys.argv[3], sys.argv[4])
