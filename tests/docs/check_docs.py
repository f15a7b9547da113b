#!/usr/bin/env python3
"""Checks the user documentation (README.md and docs/*.md) the way a reader would follow it.

A reader who clicks a link must land on a file that exists and, for `#anchor`, on a heading of
that file (GitHub's anchor rule: lower case, punctuation dropped, spaces as hyphens, repeats
numbered). The Quick start must show exactly the two commands a newcomer runs, and each must be a
script of the repository; CI (.ci/run) must still run the second. Every page in docs/ must be in
the README's contents and link back to it. docs/incoming-*.md are drafts being folded in and are
not checked.

A clone is all a reader has, so no file of the repository (code comments and scripts too) may
point at files beside it (a sibling folder of the clone, an absolute path of a developer's
machine), and docs/layout.md names every folder: each folder two levels deep has its own row, and a deeper one
is named (`name/`) in the row of the folder above it, unless it is a tests/ folder mirroring a
folder of the same path outside tests/.

Usage: check_docs.py REPOSITORY_ROOT. Prints each problem as file:line: reason; exit 1 if any.
"""
import os
import re
import sys

QUICK_START_COMMANDS = ["./deploy/demo.sh", "./deploy/test.sh"]
CI_SCRIPT = ".ci/run"

FENCE = re.compile(r"^\s*(```|~~~)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
INLINE_CODE = re.compile(r"(`+)(.+?)\1")
# [text](target) or [text](target "title"); the text may hold one level of brackets.
LINK = re.compile(r"\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]*)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(\s+.*)?$")
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def prose(text):
    """The text with fenced code blocks and inline code blanked, line breaks kept, so a link
    that wraps over lines is still found and its line number stays right."""
    out = []
    in_fence = None
    for line in text.split("\n"):
        fence = FENCE.match(line)
        if fence:
            marker = fence.group(1)
            if in_fence is None:
                in_fence = marker
            elif marker == in_fence:
                in_fence = None
            out.append("")
        elif in_fence is not None:
            out.append("")
        else:
            out.append(INLINE_CODE.sub(lambda m: " " * len(m.group(0)), line))
    return "\n".join(out)


def slug(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link's text only
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        with open(path, encoding="utf-8") as f:
            text = f.read()
        seen = {}
        found = set()
        in_fence = None
        for line in text.split("\n"):
            fence = FENCE.match(line)
            if fence:
                in_fence = None if in_fence == fence.group(1) else (in_fence or fence.group(1))
                continue
            heading = HEADING.match(line) if in_fence is None else None
            if not heading:
                continue
            base = slug(heading.group(2))
            count = seen.get(base, 0)
            seen[base] = count + 1
            found.add(base if count == 0 else f"{base}-{count}")
        cache[path] = found
    return cache[path]


def links(text):
    """(line number, target) of every inline link and reference definition outside code."""
    plain = prose(text)
    for match in LINK.finditer(plain):
        yield plain.count("\n", 0, match.start()) + 1, match.group(1)
    for number, line in enumerate(plain.split("\n"), start=1):
        definition = REFERENCE_DEFINITION.match(line)
        if definition:
            yield number, definition.group(1)


def check_links(root, path, problems):
    with open(path, encoding="utf-8") as f:
        text = f.read()
    where = os.path.relpath(path, root)
    for number, target in links(text):
        if not target or SCHEME.match(target):
            continue  # external (https:, mailto:) links are not followed here
        file_part, _, anchor = target.partition("#")
        resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part \
            else path
        if os.path.relpath(resolved, root).startswith(".."):
            problems.append(f"{where}:{number}: link '{target}' leaves the repository")
            continue
        if not os.path.exists(resolved):
            problems.append(f"{where}:{number}: link '{target}': no file "
                            f"{os.path.relpath(resolved, root)}")
            continue
        if anchor:
            if not resolved.endswith(".md") or os.path.isdir(resolved):
                problems.append(f"{where}:{number}: link '{target}': an anchor into a file "
                                "that is not markdown")
            elif anchor not in anchors(resolved):
                problems.append(f"{where}:{number}: link '{target}': no heading "
                                f"'#{anchor}' in {os.path.relpath(resolved, root)}")
    return text


def section(text, title):
    """The lines of the `## title` section (up to the next heading of its level or above)."""
    lines = text.split("\n")
    for i, line in enumerate(lines):
        heading = HEADING.match(line)
        if heading and heading.group(2).startswith(title):
            level = len(heading.group(1))
            body = []
            for rest in lines[i + 1:]:
                other = HEADING.match(rest)
                if other and len(other.group(1)) <= level:
                    break
                body.append(rest)
            return body
    return None


def check_quick_start(root, readme, problems):
    body = section(readme, "Quick start")
    if body is None:
        problems.append("README.md: no 'Quick start' section")
        return
    blocks, block = [], None
    for line in body:
        if FENCE.match(line):
            if block is None:
                block = []
            else:
                blocks.append(block)
                block = None
        elif block is not None:
            block.append(line)
    if len(blocks) != 1:
        problems.append(f"README.md: the Quick start should show one code block, it has {len(blocks)}")
        return
    commands = [line.split("#", 1)[0].strip() for line in blocks[0]]
    commands = [c for c in commands if c]
    if commands != QUICK_START_COMMANDS:
        problems.append(f"README.md: the Quick start shows {commands}, "
                        f"expected exactly {QUICK_START_COMMANDS}")
    for command in QUICK_START_COMMANDS:
        script = os.path.join(root, command)
        if not (os.path.isfile(script) and os.access(script, os.X_OK)):
            problems.append(f"README.md: Quick start command {command} is not an executable script")
    ci = os.path.join(root, CI_SCRIPT)
    if CI_SCRIPT in readme:
        with open(ci, encoding="utf-8") as f:
            ci_lines = [l.strip() for l in f]
        if QUICK_START_COMMANDS[1] not in ci_lines:
            problems.append(f"README.md says CI runs {CI_SCRIPT}, which no longer runs "
                            f"{QUICK_START_COMMANDS[1]}")


def check_pages(root, readme, pages, problems):
    readme_targets = {os.path.normpath(t.partition("#")[0]) for _, t in links(readme)}
    for page in pages:
        name = os.path.relpath(page, root)
        if name not in readme_targets:
            problems.append(f"{name}: not in the README's contents")
        with open(page, encoding="utf-8") as f:
            text = f.read()
        # The first paragraph after the title says what the page covers and links back.
        paragraphs = [p for p in re.split(r"\n\s*\n", text) if p.strip()]
        if len(paragraphs) < 2 or "../README.md" not in paragraphs[1]:
            problems.append(f"{name}: its first paragraph does not link back to ../README.md")


# A path that leaves the repository: the project's notes in the folder beside the clone (its
# name is spelled with a character class so that this line does not match itself), or a
# developer machine's absolute path.
OUTSIDE_REFERENCE = re.compile(r"(?:\.\./)+shar[e]d/|/work/(?:shar[e]d|main|wt)\b|\bseed/000_")
SKIPPED_DIRS = {".git", "node_modules", "__pycache__"}
TEXT_SUFFIXES = {".md", ".h", ".cc", ".cc.in", ".txt", ".py", ".pyi", ".sh", ".cmake", ".proto",
                 ".idl", ".xml", ".yml", ".yaml", ".conf", ".html", ".in", ".csv", ".json", ""}


def repository_files(root):
    """Every file of the repository (git's list when there is one; else a walk that skips build
    trees, which hold absolute paths of the machine they were built on)."""
    try:
        import subprocess
        listed = subprocess.run(["git", "-C", root, "ls-files", "-z"], capture_output=True,
                                check=True).stdout.decode("utf-8").split("\0")
        return [f for f in listed if f]
    except (OSError, subprocess.CalledProcessError):
        found = []
        for directory, dirs, files in os.walk(root):
            dirs[:] = [d for d in dirs if d not in SKIPPED_DIRS and not d.startswith("build")]
            found += [os.path.relpath(os.path.join(directory, f), root) for f in files]
        return found


def check_outside_references(root, files, problems):
    this = os.path.relpath(os.path.abspath(__file__), root)
    for name in files:
        suffix = os.path.splitext(name)[1]
        if name == this or suffix not in TEXT_SUFFIXES or not os.path.isfile(os.path.join(root, name)):
            continue
        try:
            with open(os.path.join(root, name), encoding="utf-8") as f:
                lines = f.read().split("\n")
        except UnicodeDecodeError:
            continue  # binary
        for number, line in enumerate(lines, start=1):
            match = OUTSIDE_REFERENCE.search(line)
            if match:
                problems.append(f"{name}:{number}: '{match.group(0)}' points outside the "
                                "repository; a clone does not have it")


def check_layout(root, files, problems):
    path = os.path.join(root, "docs", "layout.md")
    if not os.path.isfile(path):
        problems.append("docs/layout.md: missing")
        return
    with open(path, encoding="utf-8") as f:
        text = f.read()
    rows = {}
    for line in text.split("\n"):
        row = re.match(r"^\|\s*`([^`]+/)`\s*\|", line)
        if row:
            rows[row.group(1).rstrip("/")] = line
    folders = sorted({os.path.dirname(f) for f in files if os.path.dirname(f)} |
                     {d for f in files for d in [os.path.dirname(os.path.dirname(f))] if d})
    for folder in folders:
        parts = folder.split("/")
        if parts[0].startswith("."):
            continue  # .ci/ and the like have their row by name; hidden tool folders do not
        if len(parts) <= 2:
            if folder not in rows:
                problems.append(f"docs/layout.md: no row for `{folder}/`")
            continue
        if parts[0] == "tests" and os.path.isdir(os.path.join(root, *parts[1:])):
            continue  # mirrors the folder it tests
        parent = "/".join(parts[:-1])
        while parent and parent not in rows:
            parent = "/".join(parent.split("/")[:-1])
        if not parent or f"`{parts[-1]}/`" not in rows[parent]:
            problems.append(f"docs/layout.md: `{folder}/` is named in no row "
                            f"(put `{parts[-1]}/` in the row of `{parent or parts[0]}/`)")


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().split("\n\n")[-1], file=sys.stderr)
        return 2
    root = os.path.abspath(sys.argv[1])
    docs = os.path.join(root, "docs")
    pages = sorted(os.path.join(docs, n) for n in os.listdir(docs)
                   if n.endswith(".md") and not n.startswith("incoming-")) \
        if os.path.isdir(docs) else []
    problems = []
    readme = check_links(root, os.path.join(root, "README.md"), problems)
    for page in pages:
        check_links(root, page, problems)
    check_quick_start(root, readme, problems)
    check_pages(root, readme, pages, problems)
    files = repository_files(root)
    check_outside_references(root, files, problems)
    check_layout(root, files, problems)
    for problem in problems:
        print(problem)
    print(f"checked README.md and {len(pages)} pages in docs/: "
          f"{len(problems)} problem(s)" if problems else
          f"checked README.md and {len(pages)} pages in docs/: every link resolves")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
