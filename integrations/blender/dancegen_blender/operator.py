"""The Dance operator: runs `dancegen generate` as a separate process and imports the result.

From the panel's button it runs modal: the binary works in the background, its progress shows
in the status bar, Esc cancels it, and Blender stays usable. Called from a script (or in
Blender's background mode) it runs to the end before returning.
"""

import os
import queue
import shutil
import subprocess
import tempfile
import threading

import bpy

from . import command, scene_import
from .command import Request, RequestError
from .settings import preferences


class Job:
    """One run of the binary; its stderr read line by line on a thread."""

    def __init__(self, argv):
        self.argv = argv
        self.proc = subprocess.Popen(
            argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
            text=True, encoding="utf-8", errors="replace",
        )
        self.lines = []
        self.fresh = queue.Queue()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.proc.stderr:
            self.lines.append(line)
            self.fresh.put(line)

    def progress(self):
        """The newest progress line since the last call, if any."""
        newest = None
        while True:
            try:
                p = command.parse_line(self.fresh.get_nowait())
            except queue.Empty:
                return newest
            if p is not None:
                newest = p

    def done(self):
        return self.proc.poll() is not None and not self.reader.is_alive()

    def wait(self):
        self.proc.wait()
        self.reader.join()

    def cancel(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.reader.join()


def export_character(context, folder):
    """The selected armature (and the meshes it deforms) as a temporary .glb."""
    arm = context.active_object
    if arm is None or arm.type != "ARMATURE":
        raise RequestError("Select the armature to dance on (or untick 'On the selected armature').")
    keep = [o for o in context.selected_objects]
    for o in context.view_layer.objects:
        o.select_set(False)
    arm.select_set(True)
    for child in arm.children_recursive:
        if child.type == "MESH":
            child.select_set(True)
    path = os.path.join(folder, "character.glb")
    try:
        bpy.ops.export_scene.gltf(filepath=path, export_format="GLB", use_selection=True,
                                  export_animations=False)
    finally:
        for o in context.view_layer.objects:
            o.select_set(o in keep)
    return path


class DANCEGEN_OT_dance(bpy.types.Operator):
    bl_idname = "dancegen.dance"
    bl_label = "Dance"
    bl_description = "Make a dance for the song with dancegen and bring it into the scene"
    bl_options = {"REGISTER", "UNDO"}

    def _start(self, context):
        s = context.scene.dancegen
        prefs = preferences(context)
        binary = bpy.path.abspath(prefs.binary) if prefs.binary else shutil.which("dancegen")
        if not binary or not os.path.isfile(binary):
            raise RequestError(
                "No dancegen program: set its path in Preferences > Add-ons > dancegen, or put "
                f"dancegen on PATH{' (not found: ' + binary + ')' if binary else ''}."
            )
        folder = bpy.path.abspath(prefs.keep_dir) if prefs.keep_dir else tempfile.mkdtemp(prefix="dancegen-")
        os.makedirs(folder, exist_ok=True)
        self.folder = folder
        self.glb = os.path.join(folder, "dance.glb")
        self.song = bpy.path.abspath(s.song) if s.song else ""
        self.start_s = s.start
        request = Request(
            song=self.song,
            system=s.system,
            seed=s.seed,
            start=s.start,
            end=s.end,
            leader=bpy.path.abspath(s.leader) if s.leader else None,
            dancers=s.dancers,
            outputs=[self.glb, os.path.join(folder, "dance.npy")],
        )
        request.check()
        self.onto = None
        if s.use_character:
            if s.system == "group":
                raise RequestError(command.CHARACTER_ALONE)
            request.character = export_character(context, folder)
            self.onto = context.active_object
        s.last_error = ""
        self.job = Job(request.argv(binary))

    def _fail(self, context, message):
        context.scene.dancegen.last_error = message
        self.report({"ERROR"}, message)
        return {"CANCELLED"}

    def _finish(self, context):
        if self.job.proc.returncode != 0:
            return self._fail(context, command.error_words(self.job.lines, self.job.proc.returncode))
        try:
            armatures = scene_import.import_dance(context, self.glb, self.song, self.start_s,
                                                  onto=self.onto)
        except RuntimeError as e:
            return self._fail(context, f"The dance could not be brought in: {e}")
        context.scene.dancegen.last_dir = self.folder
        scene = context.scene
        self.report({"INFO"}, f"dancegen: {len(armatures)} dancer(s), frames "
                              f"{scene.frame_start}-{scene.frame_end}")
        return {"FINISHED"}

    def execute(self, context):
        try:
            self._start(context)
        except (RequestError, OSError) as e:
            return self._fail(context, str(e))
        self.job.wait()
        return self._finish(context)

    def invoke(self, context, event):
        try:
            self._start(context)
        except (RequestError, OSError) as e:
            return self._fail(context, str(e))
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        wm.progress_begin(0, 100)
        context.workspace.status_text_set("dancegen: starting… (Esc cancels)")
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        if event.type == "ESC":
            self.job.cancel()
            self._end(context)
            self.report({"WARNING"}, "dancegen: cancelled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        p = self.job.progress()
        if p is not None:
            context.window_manager.progress_update(100 * p.fraction)
            context.workspace.status_text_set(p.words() + " (Esc cancels)")
        if not self.job.done():
            return {"PASS_THROUGH"}
        self._end(context)
        return self._finish(context)
