"""Screenshot of the add-on's panel for the README, from Blender with its window on a virtual
display (Debian's xvfb and xdotool):

    python3 integrations/blender/build_zip.py /tmp/dancegen_blender.zip
    BLENDER_USER_SCRIPTS=/tmp/blender-scripts xvfb-run -s "-screen 0 1600x900x24" \
        blender --factory-startup --python integrations/blender/screenshot_panel.py -- \
        /tmp/dancegen_blender.zip SONG OUT.png

Installs the add-on from the zip, chooses a song in its panel, clicks the sidebar's dancegen
tab as a user would (Blender 3.4 has no API for a sidebar's active tab; the place is that of
the factory layout on a 1600 x 900 screen), saves the window and quits. The splash screen is
closed by a click beside it first, and the sidebar opened.
"""

import subprocess
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
zip_path, song, out = argv[:3]

bpy.ops.preferences.addon_install(filepath=zip_path, overwrite=True)
bpy.ops.preferences.addon_enable(module="dancegen_blender")
s = bpy.context.scene.dancegen
s.song = song
s.seed = 3
s.end = 30.0

# Screen pixels (from the top left) of a free spot in the viewport and of the sidebar's
# "dancegen" tab, in the factory layout at 1600 x 900.
FREE_SPOT = (300, 650)
DANCEGEN_TAB = (1308, 257)


def click(x, y):
    # In the background: Blender must see the pointer arrive (its event loop runs only after
    # this timer returns) before the click.
    subprocess.Popen(["xdotool", "mousemove", str(x), str(y), "sleep", "0.5", "click", "1"])


def close_splash():
    click(*FREE_SPOT)
    window = bpy.context.window_manager.windows[0]
    for area in window.screen.areas:
        if area.type == "VIEW_3D":
            area.spaces.active.show_region_ui = True
            area.tag_redraw()


def open_tab():
    click(*DANCEGEN_TAB)


def save():
    window = bpy.context.window_manager.windows[0]
    with bpy.context.temp_override(window=window, screen=window.screen, area=window.screen.areas[0]):
        bpy.ops.screen.screenshot(filepath=out)
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(close_splash, first_interval=1.5)
bpy.app.timers.register(open_tab, first_interval=2.5)
bpy.app.timers.register(save, first_interval=5.0)
