"""The `dancegen generate` command line for a request, and its progress lines.

No bpy here: what the panel asks for becomes the binary's flags (named as the CLI names them),
and the binary's `--progress json` lines on stderr become progress and error words.
"""

import json
import re
from dataclasses import dataclass, field
from typing import List, Optional

SYSTEMS = ("solo", "duet", "group", "holistic")

# Stages as `dancegen generate` names them in its progress lines (dancegen_generate::progress
# and each system's parts), in the web app's words for the status bar.
STAGE_WORDS = {
    "load_model": "Loading the dance model",
    "analyse_song": "Listening to the song",
    "choreography": "Planning the choreography",
    "denoising": "Creating the movement",
    "tokens": "Creating the movement",
    "write_outputs": "Saving the files",
    "render_video": "Rendering the video",
    "done": "Finishing",
}


CHARACTER_ALONE = (
    "A character dances alone and a group has several dancers: choose solo, holistic or duet "
    "(the partner), or leave the character out."
)


class RequestError(ValueError):
    """A request the binary would refuse, said before it is started."""


@dataclass
class Request:
    song: str
    system: str = "solo"
    seed: int = 0
    start: float = 0.0
    # 0: to the end of the song (a duet: as long as its leader).
    end: float = 0.0
    leader: Optional[str] = None
    dancers: int = 3
    character: Optional[str] = None
    outputs: List[str] = field(default_factory=list)

    def check(self):
        if not self.song:
            raise RequestError("Choose a song file first.")
        if self.system not in SYSTEMS:
            raise RequestError(f"Unknown system '{self.system}': choose {', '.join(SYSTEMS)}.")
        if self.system == "duet" and not self.leader:
            raise RequestError("A duet dances with a leader: choose the leader's motion file.")
        if self.character and self.system == "group":
            raise RequestError(CHARACTER_ALONE)
        if self.start < 0 or self.end < 0:
            raise RequestError("Start and end are seconds of the song, 0 or more.")
        if self.end and self.end <= self.start:
            raise RequestError(f"End ({self.end} s) must come after start ({self.start} s).")
        if not self.outputs:
            raise RequestError("No output file.")

    def argv(self, binary):
        """The command line, after [`check`]."""
        self.check()
        argv = [binary, "generate", self.song, "--system", self.system, "--seed", str(self.seed),
                "--progress", "json"]
        if self.start:
            argv += ["--start", repr(float(self.start))]
        if self.end and self.system != "duet":
            argv += ["--end", repr(float(self.end))]
        if self.system == "duet":
            argv += ["--leader", self.leader]
        if self.system == "group":
            argv += ["--dancers", str(self.dancers)]
        if self.character:
            argv += ["--character", self.character]
            if self.system == "duet":
                # The character is the generated partner; the leader stays out of the file.
                argv += ["--follower-only"]
        for o in self.outputs:
            argv += ["-o", o]
        return argv


@dataclass
class Progress:
    stage: str
    fraction: float
    eta_s: Optional[float]

    def words(self):
        stage = STAGE_WORDS.get(self.stage, self.stage.replace("_", " ").capitalize())
        eta = f", about {self.eta_s:.0f} s left" if self.eta_s is not None else ""
        return f"dancegen: {stage}… {100 * self.fraction:.0f} %{eta}"


def parse_line(line):
    """A `--progress json` line as Progress; None for any other line (the binary's words)."""
    line = line.strip()
    if not line.startswith("{"):
        return None
    try:
        obj = json.loads(line)
        return Progress(str(obj["stage"]), float(obj["fraction"]), obj.get("eta_s"))
    except (ValueError, KeyError, TypeError):
        return None


_ANSI = re.compile(r"\x1b\[[0-9;]*m")


def error_words(lines, returncode):
    """What a failed run said, as one message: the binary's `error: …` lines (its own words),
    else whatever else it printed that was not progress."""
    said = [_ANSI.sub("", l).strip() for l in lines if parse_line(l) is None]
    said = [l for l in said if l]
    errors = [l[len("error: "):] for l in said if l.startswith("error: ")]
    if errors or said:
        return " ".join(errors or said)
    return f"dancegen stopped with exit code {returncode} and said nothing"
