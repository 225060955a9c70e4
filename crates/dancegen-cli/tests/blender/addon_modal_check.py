"""The add-on's Dance button as a user presses it: Blender with its window (under Xvfb), the
operator invoked as the panel invokes it (modal), and what the user sees meanwhile. Run by the
add-on's test (crates/dancegen-cli/tests/cli_blender_addon.rs):

    xvfb-run -a blender --factory-startup -noaudio --enable-event-simulate \
        --python addon_modal_check.py -- ZIP BINARY OUT_DIR REPORT.json CASE SONG

CASE `finish`: a 4-second solo runs to its end. `cancel`: a 40-second solo, Esc pressed (a
simulated key event) once its progress has started. The report (JSON): how often a 0.1 s timer
of Blender's own fired while the dance was being made (the UI was not blocked), the progress
the operator put in the status bar, whether the binary was still running after Esc, and what
came into the scene.
"""

import json
import os
import sys
import time

import bpy

ADDON = "dancegen_blender"
TIMEOUT_S = 600

state = {"ticks_while_running": 0, "status": [], "jobs": [], "phase": "start"}


def view3d(window):
    for area in window.screen.areas:
        if area.type == "VIEW_3D":
            region = next(r for r in area.regions if r.type == "WINDOW")
            return area, region
    raise RuntimeError("no 3D view in the window")


def watch_jobs():
    """Records each job the operator starts and each status line it shows."""
    from dancegen_blender import operator

    job_init, job_progress = operator.Job.__init__, operator.Job.progress

    def init(self, argv):
        job_init(self, argv)
        state["jobs"].append(self)

    def progress(self):
        p = job_progress(self)
        if p is not None:
            state["status"].append([p.fraction, p.words()])
        return p

    operator.Job.__init__, operator.Job.progress = init, progress


def finish(report_path, report):
    with open(report_path, "w") as f:
        json.dump(report, f, indent=1)
    window = bpy.context.window_manager.windows[0]
    with bpy.context.temp_override(window=window):
        bpy.ops.wm.quit_blender()


def main():
    argv = sys.argv[sys.argv.index("--") + 1:]
    zip_path, binary, out_dir, report_path, case, song = argv[:6]
    bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
    bpy.ops.preferences.addon_enable(module=ADDON)
    watch_jobs()
    prefs = bpy.context.preferences.addons[ADDON].preferences
    prefs.binary = binary
    prefs.keep_dir = out_dir
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)
    scene = bpy.context.scene
    s = scene.dancegen
    s.song, s.system, s.seed, s.start = song, "solo", 2, 0.0
    s.end = 4.0 if case == "finish" else 40.0
    started = time.monotonic()

    def tick():
        try:
            return step()
        except Exception as e:  # report, never hang
            finish(report_path, {"error": f"{type(e).__name__}: {e}"})
            return None

    def step():
        window = bpy.context.window_manager.windows[0]
        if state["phase"] == "start":
            area, region = view3d(window)
            with bpy.context.temp_override(window=window, area=area, region=region):
                result = bpy.ops.dancegen.dance("INVOKE_DEFAULT")
            state["invoke"] = sorted(result)
            state["phase"] = "running"
            return 0.1
        job = state["jobs"][-1] if state["jobs"] else None
        running = job is not None and job.proc.poll() is None
        if running:
            state["ticks_while_running"] += 1
        armatures = [o.name for o in scene.objects if o.type == "ARMATURE"]
        if case == "cancel" and state["phase"] == "running" and state["status"] \
                and state["status"][-1][0] > 0:
            window.event_simulate(type="ESC", value="PRESS")
            window.event_simulate(type="ESC", value="RELEASE")
            state["phase"] = "cancelled"
            state["esc_at_fraction"] = state["status"][-1][0]
            state["cancel_at"] = time.monotonic()
            return 0.1
        if job is not None and not running and "ended_at" not in state:
            state["ended_at"] = time.monotonic()
        # Finished: the dance came in, or the binary ended a while ago (the operator imports
        # within a tick of its end, or reports an error).
        ended_long_ago = "ended_at" in state and time.monotonic() - state["ended_at"] > 5.0
        done = (case == "finish" and (armatures or ended_long_ago)) or (
            case == "cancel" and state["phase"] == "cancelled"
            and time.monotonic() - state["cancel_at"] > 2.0)
        if done or time.monotonic() - started > TIMEOUT_S:
            finish(report_path, {
                "error": None,
                "timed_out": not done,
                "invoke": state.get("invoke"),
                "ticks_while_running": state["ticks_while_running"],
                "status": state["status"],
                "esc_at_fraction": state.get("esc_at_fraction"),
                "binary_running_at_end": running,
                "binary_exit_code": None if job is None else job.proc.returncode,
                "armatures": armatures,
                "frame_range": [scene.frame_start, scene.frame_end],
                "files": sorted(os.listdir(out_dir)),
                "last_error": s.last_error,
            })
            return None
        return 0.1

    bpy.app.timers.register(tick, first_interval=1.0)


main()
