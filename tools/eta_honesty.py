#!/usr/bin/env python3
"""How honest the web app's "time left" is: submits SONG to a running `dancegen serve` JOBS
times (seeds 1.., solo unless PARAMS says otherwise), polls the job every second, and prints
at about ten moments the progress, the ETA and the end it predicts against the real end.

    python3 tools/eta_honesty.py http://127.0.0.1:8080 SONG [JOBS] [PARAMS_JSON]

The first job plans with the reference speeds (`dancegen_generate::time_plan`), later ones
with this machine's measured speeds. Standard library only (3.9+), plus `curl` for the upload.
"""

import json
import subprocess
import sys
import time
import urllib.request


def main(argv):
    if len(argv) < 2:
        raise SystemExit(__doc__)
    base, song = argv[0].rstrip("/"), argv[1]
    jobs = int(argv[2]) if len(argv) > 2 else 2
    extra = json.loads(argv[3]) if len(argv) > 3 else {}
    for seed in range(1, jobs + 1):
        params = json.dumps({**extra, "seed": seed})
        out = subprocess.run(["curl", "-s", "-F", f"params={params}", "-F", f"song=@{song}",
                              f"{base}/api/jobs"], capture_output=True, text=True, check=True)
        reply = json.loads(out.stdout)
        if "id" not in reply:
            raise SystemExit(f"the server refused the job: {reply}")
        started, rows = time.time(), []
        while True:
            job = json.load(urllib.request.urlopen(f"{base}/api/jobs/{reply['id']}"))
            t = time.time() - started
            if job["state"] == "running" and job["eta_s"] is not None:
                rows.append((t, job["progress"], job["eta_s"], job["stage"]))
            if job["state"] in ("done", "failed", "cancelled"):
                break
            time.sleep(1)
        total = time.time() - started
        print(f"job {seed}: {job['state']} in {total:.1f} s")
        for t, p, eta, stage in rows[::max(1, len(rows) // 10)]:
            print(f"  at {t:5.1f} s: {100 * p:4.0f} % {stage:14s} {eta:5.1f} s left -> "
                  f"ends at {t + eta:5.1f} s ({t + eta - total:+.1f} s)")


if __name__ == "__main__":
    main(sys.argv[1:])
