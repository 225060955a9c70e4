"""Zips the add-on for Blender's Preferences > Add-ons > Install:

    python3 integrations/blender/build_zip.py [OUT.zip]    (default: dancegen_blender.zip here)

The zip holds the folder dancegen_blender/ with its .py files, as Blender expects.
"""

import os
import sys
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))


def build(out):
    src = os.path.join(HERE, "dancegen_blender")
    names = sorted(n for n in os.listdir(src) if n.endswith(".py"))
    tmp = out + ".tmp"
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for n in names:
            z.write(os.path.join(src, n), f"dancegen_blender/{n}")
    os.replace(tmp, out)
    return out


if __name__ == "__main__":
    print(build(os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "dancegen_blender.zip")))
