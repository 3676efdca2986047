#!/usr/bin/env python3
"""Runs or checks every command line of README.md and docs/*.md against the built programs.

    doc_commands_test.py --source-dir SRC --build-dir BUILD [--only DOC]

Every fenced code block of the documents is read, `\\` continuations joined, heredocs and
`for ... done` loops kept whole. A line is a command of the project when its first word is one of
PROGRAMS (bare, as on PATH, or as build/.../NAME) or a scripts/ file. Three kinds:

- examples: every line of a ```sh block, and lines of a plain ``` block that carry no synopsis
  grammar (`[`, `|`, `...`). Commands of the project are RUN with bash, with the build's programs
  first on PATH, each with a timeout, and must exit 0, or the status the line's comment documents
  (`# exit 78`, `# exits 2`).
- transcripts: `$ COMMAND` lines of a plain block, run as examples; each output line the document
  shows after it that has no `...` and no decimal number (numbers may vary in the last digits)
  must appear in the command's stdout or stderr (whitespace-normalised).
- synopses: lines of a plain block with `[`, `|` or `...`, and `code spans` of the prose that
  start with a program and name an option: the program and subcommand must exist, and every
  option the line names must appear in that program's (subcommand's) --help.

Where commands run: a fresh directory per document holding copies of the repository's config/
and tests/data/ and links build -> BUILD and scripts -> SRC/scripts, so the documents' relative
paths (config/..., tests/data/..., build/sim/canalsim) resolve as from the checkout and
their outputs (m.json, pool2-report/, ...) land in that directory, never in the source tree.
The commands of one document run in document order in its directory (an example may read the
file an earlier one wrote). HOME is a directory holding ~/.config/canalid/site1.key (a key as
docs/deployment.md makes it), and LCM_DEFAULT_URL a log file there, so nothing goes to the network.
A path an `install SRC DEST` line of the same document installs to (/etc/canalidd/canalidd.toml)
is replaced by its SRC. Servers run in their validation form: canalidd and `canalsim serve`
lines get --check-config appended when they lack it, which checks the invocation and its files.

Lines that cannot run here are listed in EXCEPTIONS (document, command start, reason) and
NOT_OURS (first word of a ```sh line that is not a program of the project, e.g. systemctl). The
test fails when a ```sh line is in neither, and when a listed entry no longer occurs in the
documents, so neither list can rot. The sources of every `install` line must exist.

Prints each command with its result, then one summary line; a failure names the document, the
line and the command. Exit 0 when everything passed, 1 otherwise.
"""

import argparse
import glob
import os
import re
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field

PROGRAMS = {
    "canalid": "daemon/canalid/canalid",
    "canalidd": "daemon/canalidd/canalidd",
    "canalid-command": "daemon/command/canalid-command",
    "canalsim": "sim/canalsim",
}

# (document, start of the command line, why it is not run).
EXCEPTIONS = [
    ("README.md", "scripts/demo", "starts canalsim and canalidd for a whole PRBS experiment: "
     "2-5 minutes; the daemon suites run the same programs"),
    ("README.md", "scripts/test", "runs every test, this one included"),
    ("README.md", "scripts/setup", "installs Debian packages with apt-get (root)"),
    ("README.md", "scripts/build", "builds the whole tree (minutes); this test runs from a build"),
    ("README.md", "scripts/format --fix", "rewrites the sources in place; scripts/test runs the "
     "check"),
    ("README.md", "canalid replay run.lcmlog", "needs the LCM log of a live canalidd run "
     "(scripts/demo writes one); tests/daemon replays live runs"),
    ("README.md", "scripts/package", "a whole Release build (minutes); tests/package/"
     "install_deb.sh packages the build tree and installs it into a fresh Debian root"),
    ("docs/deployment.md", "scripts/package", "a whole Release build (minutes); tests/package/"
     "install_deb.sh packages the build tree and installs it into a fresh Debian root"),
    ("docs/deployment.md", "scripts/setup", "installs Debian packages with apt-get (root)"),
    ("docs/deployment.md", "scripts/build", "builds the whole tree (minutes); this test runs from "
     "a build"),
    ("docs/model-json.md", "canalid export run.lcmlog", "needs the LCM log of a live canalidd "
     "run; DaemonCanalsim.EveryOnlineKindIsReproducedByReplayAndIdentify runs it on one"),
    ("docs/model-json.md", "canalid identify --model frac-foptd --online --config", "reads the "
     "export of a live run (the line before); the daemon suite runs it"),
    ("docs/dashboard.md", "canalid dashboard --lcm-url", "serves until stopped; "
     "tests/dashboard/dashboard_live_test.cc runs it beside canalsim and canalidd"),
    ("docs/dashboard.md", "canalid dashboard --config", "serves until stopped; "
     "tests/dashboard/dashboard_app_test.cc and the live suite run it"),
    ("docs/reliability.md", "scripts/fuzz", "builds a second tree with clang and sanitizers "
     "(tens of minutes) and fuzzes for minutes per target; ctest -L fuzz replays what it keeps"),
]

# First words of ```sh lines that are not programs of the project, and why they are not run.
NOT_OURS = {
    "cd": "cd build && ctest: runs every test, this one included",
    "apt": "installs the Debian package (root); tests/package/install_deb.sh installs it into a "
           "fresh Debian root",
    "cmake": "a whole second build (minutes); scripts/check-build-types builds every build type "
             "from a clean clone",
    "install": "installs into /usr/local and /etc (root); its sources are checked to exist",
    "systemctl": "manages the installed systemd units (root)",
    "journalctl": "reads the installed unit's journal",
    "umask": "shell setting of the key-making steps (root, /etc)",
    "openssl": "writes the command key into /etc (root)",
    "chmod": "sets the mode of the key in /etc (root)",
    "$EDITOR": "the reader edits the installed configuration",
    "mbpoll": "a Modbus master reading a canalidd's results map on port 1503; "
              "DaemonResultsMap.ScadaMastersReadWhatTheDaemonPublishes reads a live map with mbpoll "
              "(the batch area at 2014), ResultsServerTest.PymodbusAndMbpollReadTheSlot a served one",
    "cat": "writes an environment file into /etc (root)",
    "ip": "adds a multicast route (root)",
}

PLAIN_LANGS = {""}
SHELL_LANGS = {"sh", "bash", "shell", "console"}
TIMEOUT_S = 60
SERVER_FORMS = [("canalidd",), ("canalsim", "serve")]


@dataclass
class Command:
    doc: str
    line: int
    text: str  # one logical line (continuations joined); loops and heredocs keep newlines
    kind: str  # example | transcript | synopsis
    output: list = field(default_factory=list)  # transcript: the lines the document shows

    def where(self):
        return f"{self.doc}:{self.line}"


def fenced_blocks(path):
    """(info string, [(line number, text)]) of every fenced code block of a Markdown file."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    blocks, i = [], 0
    while i < len(lines):
        m = re.match(r"^\s*```\s*([\w+-]*)\s*$", lines[i])
        if m:
            body, i = [], i + 1
            while i < len(lines) and not lines[i].lstrip().startswith("```"):
                body.append((i + 1, lines[i]))
                i += 1
            blocks.append((m.group(1).lower(), body))
        i += 1
    return blocks


def logical_lines(body):
    """[(line number, text)]: `\\` continuations joined by a space; heredocs and for loops whole."""
    out, i = [], 0
    while i < len(body):
        number, text = body[i]
        while text.rstrip().endswith("\\") and i + 1 < len(body):
            i += 1
            text = text.rstrip()[:-1].rstrip() + " " + body[i][1].strip()
        heredoc = re.search(r"<<-?\s*'?(\w+)'?", strip_comment(text))
        if heredoc:
            while i + 1 < len(body):
                i += 1
                text += "\n" + body[i][1]
                if body[i][1].strip() == heredoc.group(1):
                    break
        elif re.match(r"\s*for\s", text) and not re.search(r"\bdone\b", text):
            while i + 1 < len(body):
                i += 1
                text += "\n" + body[i][1]
                if re.match(r"\s*done\b", body[i][1]):
                    break
        out.append((number, text))
        i += 1
    return out


def strip_comment(text):
    """The text before a shell comment (a # at a word start, outside quotes)."""
    quote = None
    for k, c in enumerate(text):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "#" and (k == 0 or text[k - 1].isspace()):
            return text[:k].rstrip()
    return text.rstrip()


def first_word(text):
    words = strip_comment(text.lstrip()).split()
    return words[0] if words else ""


def program_of(word):
    """The program a command's first word runs (canalid, ..., or scripts/NAME), or None."""
    if re.fullmatch(r"scripts/[\w.-]+", word):
        return word
    if word in PROGRAMS:
        return word
    for name, rel in PROGRAMS.items():
        if word == "build/" + rel:
            return name
    return None


def runs_program(text):
    """Whether a line (or a loop's body) runs a program of the project."""
    return any(program_of(first_word(part)) for part in re.split(r"\n|;|&&|\|\||\bdo\b", text))


def commands_of(doc, path):
    """The commands of one document, and the ```sh lines that are not programs of the project."""
    commands, others = [], []
    for lang, body in fenced_blocks(path):
        lines = logical_lines(body)
        if lang in SHELL_LANGS:
            for number, text in lines:
                if not strip_comment(text).strip():
                    continue
                if runs_program(text):
                    commands.append(Command(doc, number, text.strip(), "example"))
                else:
                    others.append(Command(doc, number, text.strip(), "other"))
        elif lang in PLAIN_LANGS:
            if any(text.startswith("$ ") for _, text in lines):
                for number, text in lines:
                    if text.startswith("$ "):
                        commands.append(Command(doc, number, text[2:].strip(), "transcript"))
                    elif commands and commands[-1].kind == "transcript" and text.strip():
                        commands[-1].output.append(text)
                continue
            previous = None
            for number, text in lines:
                if re.match(r"[\w/-]+( [\w-]+)?: ", text):
                    previous = None  # a message the program prints ("canalid replay: ...")
                elif program_of(first_word(text)) or (text.lstrip().startswith("for ")
                                                     and runs_program(text)):
                    synopsis = re.search(r"[\[\]|]|\.\.\.", text) is not None
                    previous = Command(doc, number, text.strip(),
                                       "synopsis" if synopsis else "example")
                    commands.append(previous)
                elif previous and previous.kind == "synopsis" and text[:1].isspace() and text.strip():
                    previous.text += " " + text.strip()  # a synopsis's indented option lines
                else:
                    previous = None
    return commands, others


def inline_commands(doc, path):
    """Synopses of the prose: `code spans` outside fences that start with a program and name an
    option (`canalid identify --online --closed-loop off`)."""
    commands, fenced = [], False
    with open(path, encoding="utf-8") as f:
        for number, text in enumerate(f, 1):
            if text.lstrip().startswith("```"):
                fenced = not fenced
                continue
            for span in [] if fenced else re.findall(r"`([^`]+)`", text):
                words = span.split()
                if (words and program_of(words[0]) and not words[0].startswith("scripts/")
                        and options_of(span)):
                    commands.append(Command(doc, number, span.strip(), "synopsis"))
    return commands


class Programs:
    def __init__(self, build_dir):
        self.build_dir = build_dir
        self.help_cache = {}

    def path(self, name):
        return os.path.join(self.build_dir, PROGRAMS[name])

    def help(self, name, sub=None):
        """(exit status, text) of `NAME [SUB] --help`."""
        key = (name, sub)
        if key not in self.help_cache:
            argv = [self.path(name)] + ([sub] if sub else []) + ["--help"]
            r = subprocess.run(argv, capture_output=True, text=True, timeout=TIMEOUT_S)
            self.help_cache[key] = (r.returncode, r.stdout + r.stderr)
        return self.help_cache[key]


def options_of(text):
    return sorted(set(re.findall(r"(?<![\w-])(--[A-Za-z0-9][\w-]*|-[A-Za-z])(?![\w-])", text)))


def check_synopsis(cmd, programs):
    """Problems of a synopsis: unknown program, subcommand or options."""
    words = strip_comment(cmd.text).split()
    name = program_of(words[0])
    if name.startswith("scripts/"):
        return []
    sub = None
    if name in ("canalid", "canalsim"):
        sub = words[1] if len(words) > 1 else ""
        status, text = programs.help(name, sub)
        if status != 0:
            return [f"'{name} {sub} --help' exits {status}: no subcommand '{sub}'"]
    status, text = programs.help(name, sub)
    if status != 0:
        return [f"'{name} --help' exits {status}"]
    missing = [o for o in options_of(cmd.text)
               if not re.search(r"(?<![\w-])" + re.escape(o) + r"(?![\w-])", text)]
    if missing:
        shown = f"{name} {sub}" if sub else name
        return [f"option {', '.join(missing)} not in '{shown} --help'"]
    return []


def documented_status(text):
    """The exit status a command's comment documents (`# exit 78`, `# exits 2`), else 0."""
    comment = text[len(strip_comment(text)):]
    m = re.search(r"\bexits?\s+(\d+)", comment)
    return int(m.group(1)) if m else 0


def installed_paths(source_dir, build_dir, others, stage):
    """DEST -> SRC of the documents' `install [-m M] SRC DEST` lines, and their missing sources
    (a source under /usr or /etc must be one the install of the build tree puts in place)."""
    mapping, problems = {}, []
    for cmd in others:
        words = strip_comment(cmd.text).split()
        if not words or words[0] != "install" or "-d" in words:
            continue
        args, k = [], 1
        while k < len(words):
            if words[k] in ("-m", "-o", "-g"):
                k += 2
                continue
            args.append(words[k])
            k += 1
        sources, dest = args[:-1], args[-1]
        sources = [staged_form(src, stage) for src in sources]
        for src in sources:
            if src.startswith(stage):
                continue
            root = build_dir if src.startswith("build/") else source_dir
            rel = src[len("build/"):] if src.startswith("build/") else src
            if not glob.glob(os.path.join(root, rel)):
                problems.append(f"{cmd.where()}: install source {src} does not exist "
                                f"(in {root})")
        if len(sources) == 1 and not dest.endswith("/"):
            mapping[dest] = sources[0]
    return mapping, problems


def prepare_directory(base, source_dir, build_dir, name):
    work = os.path.join(base, name)
    os.makedirs(os.path.join(work, "tests"))
    shutil.copytree(os.path.join(source_dir, "config"), os.path.join(work, "config"))
    shutil.copytree(os.path.join(source_dir, "tests", "data"),
                    os.path.join(work, "tests", "data"))
    os.symlink(build_dir, os.path.join(work, "build"))
    os.symlink(os.path.join(source_dir, "scripts"), os.path.join(work, "scripts"))
    return work


STAGED_PATH = re.compile(r"(?<![\w.~-])/(?:usr|etc)/[\w./@+-]*[\w@+-]")


def stage_install(build_dir, stage):
    """Installs the build tree as the package does (prefix /usr) into `stage` (cmake --install
    with DESTDIR), so documented paths under /usr and /etc are checked against what the install
    really puts there. Returns a problem, or None."""
    env = dict(os.environ, DESTDIR=stage)
    done = subprocess.run(["cmake", "--install", build_dir, "--prefix", "/usr"], env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        return "cmake --install of the build tree failed:\n" + done.stdout
    return None


def staged_form(command, stage):
    """`command` with each absolute /usr or /etc path that the install puts in place replaced by
    its staged copy (paths the install does not make are left alone)."""
    def replace(match):
        staged = stage + match.group(0)
        return staged if os.path.exists(staged) else match.group(0)
    return STAGED_PATH.sub(replace, command)


def runnable_form(text, installed, stage):
    """The command as run: installed paths replaced, servers in their validation form."""
    command = strip_comment(text)
    for dest, src in installed.items():
        command = re.sub(re.escape(dest) + r"(?![\w./-])", src, command)
    command = staged_form(command, stage)
    words = command.split()
    for form in SERVER_FORMS:
        if (program_of(words[0]) == form[0] and tuple(words[1:len(form)]) == form[1:]
                and "--check-config" not in words):
            command += " --check-config"
    return command


def run(command, work, env, log_base):
    """(exit status or None on timeout, seconds, stdout, stderr) of `bash -c COMMAND` in work."""
    out_path, err_path = log_base + ".out", log_base + ".err"
    start = time.monotonic()
    with open(out_path, "w") as out, open(err_path, "w") as err:
        proc = subprocess.Popen(["bash", "-e", "-o", "pipefail", "-c", command], cwd=work,
                                env=env, stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                start_new_session=True)
        try:
            status = proc.wait(timeout=TIMEOUT_S)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            status = None
    seconds = time.monotonic() - start
    with open(out_path, errors="replace") as f:
        stdout = f.read()
    with open(err_path, errors="replace") as f:
        stderr = f.read()
    return status, seconds, stdout, stderr


def normalise(line):
    return " ".join(line.split())


def tail(text, lines=8):
    return "\n".join("      | " + s for s in text.rstrip().split("\n")[-lines:]) if text.strip() else ""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source-dir", required=True)
    parser.add_argument("--build-dir", required=True)
    parser.add_argument("--only", help="one document, e.g. README.md")
    args = parser.parse_args()
    source_dir = os.path.abspath(args.source_dir)
    build_dir = os.path.abspath(args.build_dir)
    started = time.monotonic()

    programs = Programs(build_dir)
    missing = [programs.path(n) for n in PROGRAMS if not os.access(programs.path(n), os.X_OK)]
    if missing:
        print("doc_commands: programs not built (scripts/build canalid canalidd canalsim "
              "canalid-command): " + ", ".join(missing))
        return 1

    docs = ["README.md"] + sorted(
        "docs/" + f for f in os.listdir(os.path.join(source_dir, "docs")) if f.endswith(".md"))
    failures, counts = [], {"run": 0, "synopsis": 0, "skipped": 0}
    used_exceptions, used_words = set(), set()

    def fail(cmd, problem, detail=""):
        failures.append(f"{cmd.where()}: {cmd.text.splitlines()[0]}\n    {problem}")
        print(f"FAIL {cmd.where()}: {cmd.text.splitlines()[0]}\n     {problem}")
        if detail:
            print(detail)

    base = tempfile.mkdtemp(prefix="canalid-doc-commands-")
    try:
        home = os.path.join(base, "home")
        os.makedirs(os.path.join(home, ".config", "canalid"))
        key = os.path.join(home, ".config", "canalid", "site1.key")
        with open(os.open(key, os.O_WRONLY | os.O_CREAT, 0o600), "w") as f:
            f.write(secrets.token_hex(32) + "\n")
        env = dict(os.environ)
        env["PATH"] = os.pathsep.join(
            [os.path.dirname(programs.path(n)) for n in PROGRAMS] + [env.get("PATH", "")])
        env["HOME"] = home
        env["LCM_DEFAULT_URL"] = "file://" + os.path.join(base, "lcm.log") + "?mode=w"
        env.pop("CANALID_BUILD_DIR", None)
        stage = os.path.join(base, "stage")
        problem = stage_install(build_dir, stage)
        if problem:
            failures.append(problem)
            print("FAIL " + problem)

        for doc in docs:
            if args.only and doc != args.only:
                continue
            commands, others = commands_of(doc, os.path.join(source_dir, doc))
            commands += inline_commands(doc, os.path.join(source_dir, doc))
            installed, problems = installed_paths(source_dir, build_dir, others, stage)
            for p in problems:
                failures.append(p)
                print("FAIL " + p)
            for cmd in others:
                word = first_word(cmd.text)
                if word in NOT_OURS:
                    used_words.add(word)
                    counts["skipped"] += 1
                    print(f"skip {cmd.where()}: {cmd.text.splitlines()[0]}  ({NOT_OURS[word]})")
                else:
                    fail(cmd, f"a ```sh line that runs none of {', '.join(PROGRAMS)} or "
                         "scripts/: list its first word in NOT_OURS with the reason")
            work = None
            for index, cmd in enumerate(commands):
                words = strip_comment(cmd.text).split()
                name = program_of(words[0]) if words else None
                if name and name.startswith("scripts/") and not os.access(
                        os.path.join(source_dir, name), os.X_OK):
                    fail(cmd, f"{name} is not an executable file of the repository")
                    continue
                exception = next((e for e in EXCEPTIONS
                                  if e[0] == doc and cmd.text.startswith(e[1])), None)
                if exception:
                    used_exceptions.add(exception)
                    counts["skipped"] += 1
                    print(f"skip {cmd.where()}: {cmd.text.splitlines()[0]}  ({exception[2]})")
                    continue
                if cmd.kind == "synopsis":
                    counts["synopsis"] += 1
                    problems = check_synopsis(cmd, programs)
                    if problems:
                        fail(cmd, "; ".join(problems))
                    else:
                        print(f"ok   {cmd.where()}: {cmd.text}  (synopsis: options in --help)")
                    continue
                if work is None:
                    work = prepare_directory(base, source_dir, build_dir,
                                             doc.replace("/", "_").replace(".md", ""))
                command = runnable_form(cmd.text, installed, stage)
                expected = documented_status(cmd.text)
                status, seconds, stdout, stderr = run(
                    command, work, env, os.path.join(base, f"{doc.replace('/', '_')}-{index}"))
                counts["run"] += 1
                shown = command.replace("\n", " ").strip()
                if status is None:
                    fail(cmd, f"ran '{shown}': no exit within {TIMEOUT_S} s", tail(stderr))
                    continue
                if status != expected:
                    fail(cmd, f"ran '{shown}': exit {status}, the document says {expected}",
                         tail(stderr or stdout))
                    continue
                produced = {normalise(s) for s in (stdout + "\n" + stderr).split("\n")}
                absent = [s for s in cmd.output if "..." not in s
                          and not re.search(r"\d\.\d", s) and normalise(s) not in produced]
                if absent:
                    fail(cmd, f"ran '{shown}': the document shows output it did not print: "
                         f"{absent[0].strip()!r}", tail(stdout + stderr))
                    continue
                print(f"ok   {cmd.where()}: {shown}  (exit {status}, {seconds:.1f} s)")
    finally:
        shutil.rmtree(base, ignore_errors=True)

    if not args.only:
        for e in EXCEPTIONS:
            if e not in used_exceptions:
                failures.append(f"EXCEPTIONS lists '{e[1]}' in {e[0]}, which no longer has it")
                print("FAIL " + failures[-1])
        for word in NOT_OURS:
            if word not in used_words:
                failures.append(f"NOT_OURS lists '{word}', which no ```sh line of the documents "
                                "starts with any more")
                print("FAIL " + failures[-1])

    print(f"doc_commands: {counts['run']} commands run, {counts['synopsis']} synopses checked, "
          f"{counts['skipped']} lines not run (listed), {len(failures)} failed, "
          f"{time.monotonic() - started:.1f} s")
    for f in failures:
        print("  " + f.splitlines()[0])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
