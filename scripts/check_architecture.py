#!/usr/bin/env python3
"""The architecture rules of docs/architecture.md, read from the code (exit 1 on a breach):

1. No include circle between the folders of src/ (a folder depends on another when one of its
   files includes that folder's public header, include/cupid/<name>.h, or a private header of
   it), and none between the files of one folder.
2. No source file outside the tables switches on the coupling method or the solver engine: the
   method names (CUPID_COUPLING_FICTITIOUS, _LAGRANGE, _ARLEQUIN, `coupling.method`) appear only
   in the model reader (src/io/) and in the table lookup (src/problem/method_coupled.c); the
   engine names (CUPID_SOLVER_DIRECT, _PETSC) only in the reader and the engine table
   (src/solvers/engine.c).
3. src/app/ is the command line only: main.c and cli.c.
4. The files of src/problem/ call one another without a circle (issue 33): problem.c drives the
   stages (set-up, the analyses, the outputs), and what the stages share (progress, phases,
   checks, the agreements over the ranks: support.c; the solver engine: solver.c) lies below
   them. A call is a file naming a function that another file of the folder defines (the
   methods' stages, called through their table, are no calls).

Usage: scripts/check_architecture.py [-v] [SOURCE_DIR]   (-v: print the folder graph)
"""
import os
import re
import sys

ARGS = [a for a in sys.argv[1:] if a != "-v"]
ROOT = os.path.abspath(ARGS[0] if ARGS else os.path.join(os.path.dirname(__file__), ".."))
SRC = os.path.join(ROOT, "src")

# The folder that implements each public header.
HEADER_FOLDER = {
    "base.h": "core", "error.h": "core", "expr.h": "io", "io.h": "io", "model.h": "io",
    "pd.h": "pd", "cuf.h": "cuf", "solvers.h": "solvers", "coupling.h": "coupling",
    "dynamics.h": "dynamics", "problem.h": "problem", "app.h": "app",
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def sources():
    for folder in sorted(os.listdir(SRC)):
        d = os.path.join(SRC, folder)
        if os.path.isdir(d):
            for f in sorted(os.listdir(d)):
                if f.endswith((".c", ".h")):
                    yield folder, f, os.path.join(d, f)


def strip_comments(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def find_cycle(graph):
    """One cycle of a directed graph {node: set(nodes)} as a list, or None."""
    state, stack = {}, []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if not state.get(m):
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if not state.get(n):
            c = visit(n)
            if c:
                return c
    return None


DEFINITION = re.compile(r"^(?!static\b)[A-Za-z_][\w \*]*?\b(cupid_\w+)\s*\([^;{]*\)\s*\{", re.M)


def call_graph(texts):
    """{file: files whose (non-static) functions it names} over the .c files of one folder."""
    defined = {}
    code = {n: strip_comments(t) for n, t in texts.items() if n.endswith(".c")}
    for n, c in code.items():
        for name in DEFINITION.findall(c):
            defined[name] = n
    graph = {}
    for n, c in code.items():
        for name in set(re.findall(r"\b(cupid_\w+)\s*\(", c)):
            if name in defined and defined[name] != n:
                graph.setdefault(n, set()).add(defined[name])
    return graph


def main():
    problems = []
    folders, files = {}, {}
    texts = {}
    for folder, name, path in sources():
        text = open(path, encoding="utf-8").read()
        texts[(folder, name)] = text
        for inc in INCLUDE.findall(text):
            base = os.path.basename(inc)
            if inc.startswith("cupid/") and base in HEADER_FOLDER:
                target = HEADER_FOLDER[base]
            elif "/" in inc and inc.split("/")[0] in os.listdir(SRC):
                target = inc.split("/")[0]
            elif os.path.exists(os.path.join(SRC, folder, inc)):
                target = folder
                files.setdefault(folder, {}).setdefault(name, set()).add(base)
            else:
                continue  # generated (cupid_config.h) or a system header
            if target != folder:
                folders.setdefault(folder, set()).add(target)
    # A public header that includes another makes its folder depend on that one's (pd.h
    # including solvers.h: pd -> solvers), whoever includes it.
    inc_dir = os.path.join(ROOT, "include", "cupid")
    for h in sorted(os.listdir(inc_dir)):
        if h not in HEADER_FOLDER:
            continue
        for inc in INCLUDE.findall(open(os.path.join(inc_dir, h), encoding="utf-8").read()):
            base = os.path.basename(inc)
            if inc.startswith("cupid/") and base in HEADER_FOLDER and HEADER_FOLDER[base] != HEADER_FOLDER[h]:
                folders.setdefault(HEADER_FOLDER[h], set()).add(HEADER_FOLDER[base])
    cycle = find_cycle(folders)
    if cycle:
        problems.append("include circle between folders: " + " -> ".join(cycle))
    for folder, graph in files.items():
        # a .c includes headers; a header including a header makes an edge between headers
        hgraph = {f: {g for g in deps if g != f} for f, deps in graph.items() if f.endswith(".h")}
        cycle = find_cycle(hgraph)
        if cycle:
            problems.append("include circle in src/%s: %s" % (folder, " -> ".join(cycle)))

    method = re.compile(r"CUPID_COUPLING_(FICTITIOUS|LAGRANGE|ARLEQUIN)\b|coupling\.method\b")
    engine = re.compile(r"CUPID_SOLVER_(DIRECT|PETSC)\b")
    for (folder, name), text in texts.items():
        code = strip_comments(text)
        where = "src/%s/%s" % (folder, name)
        if folder != "io" and where != "src/problem/method_coupled.c" and method.search(code):
            problems.append("%s switches on the coupling method (%s): use the method table "
                            "(src/problem/method.h)" % (where, method.search(code).group(0)))
        if folder != "io" and where != "src/solvers/engine.c" and engine.search(code):
            problems.append("%s switches on the solver engine (%s): use the engine table "
                            "(cupid_solver_type, solvers.h)" % (where, engine.search(code).group(0)))
    app = sorted(f for (folder, f) in texts if folder == "app")
    if app != ["cli.c", "main.c"]:
        problems.append("src/app/ holds %s: it is the command line only (cli.c, main.c)" % ", ".join(app))

    cycle = find_cycle(call_graph({n: t for (f, n), t in texts.items() if f == "problem"}))
    if cycle:
        problems.append("call circle in src/problem: %s: move what the stages share to a file "
                        "below them (support.c)" % " -> ".join(cycle))

    edges = sum(len(v) for v in folders.values())
    if "-v" in sys.argv:
        for f in sorted(folders):
            print("  %s -> %s" % (f, ", ".join(sorted(folders[f]))))
    print("architecture: %d folders, %d include arrows between them, %d files" %
          (len({f for f, _ in texts}), edges, len(texts)))
    for p in problems:
        print("FAIL:", p)
    print("4 passed, 0 failed" if not problems else "%d passed, %d failed" % (max(0, 4 - len(problems)), len(problems)))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
