"""`--help` of every Hydra command, read from the command's own config file (conf/<command>.yaml): its settings,
each with its default and the one-line comment written beside it, and its config groups with the options that exist
(conf/<group>/*.yaml). The config is the one table of what a user can set, what it means and what it may be; Hydra's
own `--help` would print the composed config without a word on any setting."""

from __future__ import annotations

import re

from motiondiff.runtime.paths import CONF_DIR

SETTING = re.compile(r"^(?P<indent> {0,2})(?P<key>[A-Za-z_]\w*):\s*(?P<value>[^#\n]*?)\s*(?:#\s*(?P<note>.*))?$")
GROUP = re.compile(r"^\s+-\s+(?P<key>[A-Za-z_]\w*):\s*(?P<value>[^#\n]*?)\s*(?:#\s*(?P<note>.*))?$")
HIDDEN = {"defaults", "hydra", "task", "paths", "_self_"}
WIDTH = 26


def command_help(config_name: str) -> str:
    lines = (CONF_DIR / f"{config_name}.yaml").read_text(encoding="utf-8").splitlines()
    usage = [line[2:] for line in lines if line.startswith("# python") or line.startswith("# `make")][:4]
    groups, settings = [], []
    parent, in_defaults, above = None, False, []
    for line in lines:
        if line.startswith("#") and not line.startswith(("# python", "# `make")):  # a comment block above a key
            above.append(line.lstrip("# ").strip())
            continue
        note_above, above = " ".join(above), []
        if line.startswith("defaults:"):
            in_defaults = True
            continue
        group = GROUP.match(line) if in_defaults else None
        if group and group["key"] not in HIDDEN and (CONF_DIR / group["key"]).is_dir():
            groups.append((group["key"], group["value"], group["note"] or "", _options(group["key"])))
            continue
        if in_defaults and line.startswith((" ", "-")):
            continue
        in_defaults = False
        setting = SETTING.match(line)
        if setting is None or setting["key"] in HIDDEN:
            continue
        if setting["indent"]:  # one level of nesting: optim.lr= and the like
            if parent is not None:
                settings.append((f"{parent}.{setting['key']}", setting["value"], setting["note"] or ""))
            continue
        parent = setting["key"] if not setting["value"] else None
        if setting["value"]:
            settings.append((setting["key"], setting["value"], setting["note"] or note_above))
    out = [*(f"usage: {u}" for u in usage or [f"python {config_name}.py [key=value ...]"]), ""]
    if groups:
        out += ["config groups (group=option; the default first):"]
        for key, value, note, options in groups:
            choices = " | ".join([value, *[o for o in options if o != value]])
            out.append(_row(f"{key}={value}", f"{choices}" + (f". {note}" if note else "")))
        out.append("")
    out += ["settings (key=value; the default shown):"]
    out += [_row(f"{key}={value}", note) for key, value, note in settings]
    out += ["", "Lists are [a,b]; quote text with spaces or commas: text='a person walks, then waves'.",
            "-m key=a,b sweeps (one run each); --cfg job prints the whole composed config; --hydra-help is Hydra's."]  # fmt: skip
    return "\n".join(out)


def _options(group: str) -> list[str]:
    return sorted(p.stem for p in (CONF_DIR / group).glob("*.yaml"))


def _row(left: str, right: str) -> str:
    left = f"  {left}"
    return f"{left:<{WIDTH}} {right}" if len(left) < WIDTH else f"{left}\n{'':<{WIDTH}} {right}"
