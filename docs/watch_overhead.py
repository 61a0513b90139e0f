"""What watching a comparison costs it: the same comparison run by `compare`, by `watch` with
no page open, with a raw client reading the events (the server's own work: copies, exposure,
encoding, sockets), and with headless Chromium drawing the page (on the same cores, in
software WebGL), each repeated and alternated; medians. Standard library only.

    cargo build --release -p xtask
    python3 docs/watch_overhead.py --scene office:size=0.05 --solvers xu,stochastic-jacobi \
        --until columns=300,rays=2e7 --repeats 3
"""

import argparse
import os
import shutil
import signal
import socket
import statistics
import subprocess
import tempfile
import threading
import time

XTASK = os.path.join(os.path.dirname(__file__), "..", "target", "release", "xtask")
CHROMIUM = os.environ.get("RADIOSITY_CHROMIUM", "/usr/bin/chromium")


def table(lines, solvers):
    """Each solver's seconds, the last column of the summary table."""
    out = {}
    for line in lines:
        words = line.split()
        if words and words[0] in solvers:
            out[words[0]] = float(words[-1])
    return out


def run(mode, args, scratch):
    common = ["--scene", args.scene, "--solvers", args.solvers, "--until", args.until, "--reference", "none"]
    results = os.path.join(scratch, mode)
    if mode == "compare":
        command = [XTASK, "compare", *common, "--out", results]
    else:
        command = [XTASK, "watch", *common, "--results", results]
    start = time.monotonic()
    child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    lines, client, received = [], None, [0]
    for line in child.stdout:
        lines.append(line.rstrip("\n"))
        if line.startswith("watch the comparison at "):
            url = line.split(" at ")[1].strip()
            if mode == "watch-events":
                client = threading.Thread(target=read_events, args=(url, received), daemon=True)
                client.start()
            elif mode == "watch-chromium":
                profile = os.path.join(scratch, "profile")
                client = subprocess.Popen(
                    [CHROMIUM, "--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                     "--disable-background-networking", "--no-first-run", f"--user-data-dir={profile}",
                     "--window-size=1280,900", "--dump-dom", url + "?hold"],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if line.startswith("the comparison has ended"):
            break
    wall = time.monotonic() - start
    if mode != "compare":
        if isinstance(client, subprocess.Popen):
            client.wait(timeout=120)
        child.send_signal(signal.SIGINT)
    rest = child.stdout.read().splitlines() if mode == "compare" else []
    child.wait()
    lines += rest
    page = [l for l in lines if l.startswith("page:")]
    shutil.rmtree(results, ignore_errors=True)
    return wall, table(lines, args.solvers.split(",")), page[0] if page else ""


def read_events(url, received):
    host, port = url.removeprefix("http://").strip("/").split(":")
    with socket.create_connection((host, int(port))) as s:
        s.sendall(f"GET /events HTTP/1.1\r\nHost: {host}\r\n\r\n".encode())
        while True:
            chunk = s.recv(1 << 20)
            if not chunk or b"event: done" in chunk:
                return
            received[0] += len(chunk)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="office:size=0.05")
    parser.add_argument("--solvers", default="xu,stochastic-jacobi")
    parser.add_argument("--until", default="columns=300,rays=2e7")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    modes = ["compare", "watch", "watch-events"] + (["watch-chromium"] if os.path.exists(CHROMIUM) else [])
    measured = {m: [] for m in modes}
    with tempfile.TemporaryDirectory() as scratch:
        for rep in range(args.repeats):
            for mode in modes:
                wall, seconds, page = run(mode, args, scratch)
                measured[mode].append((wall, seconds, page))
                print(f"run {rep + 1} {mode}: {wall:.1f} s wall, solver seconds {seconds}; {page}", flush=True)
    print("\nmode | wall, median | " + " | ".join(f"{s} seconds, median" for s in args.solvers.split(",")))
    base = statistics.median(w for w, _, _ in measured["compare"])
    for mode in modes:
        wall = statistics.median(w for w, _, _ in measured[mode])
        cells = []
        for s in args.solvers.split(","):
            v = statistics.median(x[s] for _, x, _ in measured[mode])
            b = statistics.median(x[s] for _, x, _ in measured["compare"])
            cells.append(f"{v:.2f} ({v / b:.3f}×)")
        print(f"{mode} | {wall:.1f} s ({wall / base:.3f}×) | " + " | ".join(cells))


if __name__ == "__main__":
    main()
