#!/usr/bin/python3
"""Maintainers' structural check of the C++ in src/, include/, apps/ and python/.

The rule: no module cycles (modules link one way, as the data flows: src/CMakeLists.txt), and no
function over 80 lines (--max-lines; a long function hides several steps behind one name).

Cycles: a module is the first folder under src/ or include/ssta/ (apps/: apps, python/: python).
`#include "ssta/<module>/..."`, src-relative `#include "<module>/..."` and relative includes are
edges; each strongly connected component of 2+ modules is reported with a file:line per edge.

Functions: from the line of the name to the closing brace. The lexer skips comments, literals
(raw strings too) and preprocessor lines. A `{` at namespace or class scope opens a body when it
follows `(...)` and optionally qualifiers, `-> Type` or a constructor initializer list; namespace,
class, enum and initializer braces (`= {`, `x{1}`, `f(T{})`) do not. Lambdas count towards the
enclosing function; lambdas at namespace scope (static initializers) are ignored.

Exit status 1 if anything was found, 0 if clean.
"""
import argparse, os, re, sys
from collections import defaultdict, deque

FOLDERS, EXTS = ("src", "include", "apps", "python"), (".h", ".hpp", ".cpp", ".cc")
TOKEN = re.compile(r"""
    (?P<skip> /\*.*?\*/ | //[^\n]* | ^[ \t]*\#(?:\\\n|/\*.*?\*/|[^\n])* | \[\[.*?\]\] )
  | (?P<str> (?:u8|[uUL])?R"(?P<delim>[^()\\\s]*)\(.*?\)(?P=delim)"
           | (?:u8|[uUL])?"(?:\\.|[^"\\\n])*" | (?:u8|[uUL])?'(?:\\.|[^'\\\n])*' )
  | (?P<num> \.?\d(?:[eEpP][+-]|[\w.'])* )
  | (?P<tok> [A-Za-z_]\w* | :: | -> | \.\.\. | \S )""", re.S | re.M | re.X)
NOT_NAMES = {"decltype", "alignas", "__attribute__", "__declspec", "sizeof", "alignof", "noexcept",
             "static_assert", "return", "if", "while", "for", "switch", "catch", "throw"}
QUALIFIERS = {"const", "volatile", "override", "final", "&", "mutable", "constexpr", "noexcept", "throw"}


def tokens(text):
    """Yield (token, line): words, numbers as NUM, literals as STR, '::', '->', punctuation."""
    line, pos = 1, 0
    for m in TOKEN.finditer(text):
        line, pos = line + text.count("\n", pos, m.start()), m.start()
        if not m.group("skip"):
            yield m.group("tok") or ("STR" if m.group("str") else "NUM"), line


def skip(toks, k, open_, close):
    """Index after the group that opens at toks[k]; len(toks) if it does not close."""
    depth = 0
    for j in range(k, len(toks)):
        depth += (toks[j] == open_) - (toks[j] == close)
        if depth == 0:
            return j + 1
    return len(toks)


def tail_kind(toks, k):
    """What a `{` after the parameter list ending at toks[k - 1] opens: 'func' (after qualifiers,
    `-> Type` or a complete initializer list), 'other' (a member initializer `a_{`, or no tail)."""
    while k < len(toks) and toks[k] in QUALIFIERS:
        k = skip(toks, k + 1, "(", ")") if toks[k + 1:k + 2] == ["("] and toks[k] in ("noexcept", "throw") else k + 1
    if toks[k:k + 1] == ["->"]:  # trailing return type
        while k < len(toks) and toks[k] != ":":
            k = skip(toks, k, "(", ")") if toks[k] == "(" else k + 1
    if k == len(toks):
        return "func"
    if toks[k] != ":":
        return "other"
    k += 1  # constructor initializer list: name(...) or name{...}, comma separated
    while k < len(toks):
        while k < len(toks) and toks[k] not in ("(", "{}"):
            k = skip(toks, k, "<", ">") if toks[k] == "<" else k + 1
        if k == len(toks):
            return "other"  # `name` then `{`: a member's braced initializer
        k = skip(toks, k, "(", ")") if toks[k] == "(" else k + 1
        k += toks[k:k + 1] == ["..."]  # a pack expansion
        if k < len(toks) and toks[k] != ",":
            return "other"
        k += 1
    return "func"


def classify(head):
    """Kind of a `{` after the declaration head at namespace or class scope (ns, class, func or
    other), with the function's name and line when it is a body."""
    toks = [t for t, _ in head]
    if toks[:1] in (["namespace"], ["extern"]) or toks[:2] == ["inline", "namespace"]:
        return "ns", None
    if not toks or "enum" in toks or toks.count("(") != toks.count(")"):  # `f(x = {})`, `a_(T{})`
        return "other", None
    k, depth = 0, 0
    while k < len(toks):
        t, prev = toks[k], toks[k - 1] if k else ""
        if t == "=" and depth == 0:
            return "other", None
        if t == "operator" or (t == "(" and depth == 0 and (prev == ">" or re.match(r"\w+$", prev) and prev not in NOT_NAMES)):
            name = k if t == "operator" else k - 1
            if t == "operator":  # its name runs up to the parameter list: `operator()(`, `operator==(`
                k += 2 if toks[k + 1:k + 2] == ["("] else 1
                k = toks.index("(", k) if "(" in toks[k:] else len(toks)
            elif prev == ">":  # foo<T>(
                while depth or toks[name] == ">":
                    depth += (toks[name] == ">") - (toks[name] == "<")
                    name -= 1
            kind = tail_kind(toks, skip(toks, k, "(", ")")) if k < len(toks) else "other"
            return kind, func_name(head, name) if kind == "func" else None
        if t == "(":
            k = skip(toks, k, "(", ")")
            continue
        depth += (t == "<") - (t == ">") if depth or t == "<" else 0  # template arguments
        k += 1
    return ("class" if {"class", "struct", "union"} & set(toks) else "other"), None


def func_name(head, k):
    """`A::B::name` ending at head[k] (the name, or the `operator` token), and its line."""
    name = head[k][0]
    if name == "operator":
        op = "()" if head[k + 1][0] == "(" else "".join(t for t, _ in head[k + 1:k + 3] if t != "(")
        name += " " + op if op[0].isalpha() else op
    while k >= 2 and head[k - 1][0] in ("::", "~"):
        if head[k - 1][0] == "~":
            name, k = "~" + name, k - 1
            continue
        k -= 2
        if head[k][0] == ">":  # Foo<T>::
            k = max(j for j in range(k) if head[j][0] == "<") - 1
        name = head[k][0] + "::" + name
    return name, head[k][1]


def scopes(path, text):
    """Yield (kind, name, first line, last line) of each brace pair at namespace or class scope;
    kind is ns, class, func or other (enum, initializer, namespace-scope lambda)."""
    stack, head = [("ns", None, 0)], []  # open scopes: (kind, (name, line) or None, line)
    for tok, line in tokens(text):
        inside = stack[-1][0] in ("func", "other", "inner")
        if tok == "{":
            kind, name = ("inner", None) if inside else classify(head)
            stack.append((kind, name, line))
            head = head if kind in ("other", "inner") else []
        elif tok == "}" and len(stack) == 1:
            print(f"warning: {path}:{line}: unbalanced '}}'", file=sys.stderr)
        elif tok == "}":
            kind, name, start = stack.pop()
            if kind != "inner":
                yield kind, name and name[0], name[1] if name else start, line
            if stack[-1][0] in ("ns", "class"):  # an initializer's braces stay part of the head
                head = head + [("{}", line)] if kind == "other" else []
        elif inside:
            continue
        elif tok == ";" or (tok == ":" and [t for t, _ in head] in (["public"], ["private"], ["protected"])):
            head = []
        else:
            head.append((tok, line))
    if len(stack) != 1:
        print(f"warning: {path}: {len(stack) - 1} unclosed '{{'", file=sys.stderr)


def module_of(rel):
    parts = rel.split("/")
    if parts[0] in ("apps", "python"):
        return parts[0]
    if parts[:2] == ["include", "ssta"] and len(parts) > 3:
        return parts[2]
    return parts[1] if parts[0] == "src" and len(parts) > 2 else None


def include_edges(root, rel, text):
    """Yield (module, line) for each include of a module's file."""
    for no, src in enumerate(text.splitlines(), 1):
        m = re.match(r'\s*#\s*include\s*"([^"]+)"', src)
        inc = m.group(1) if m else ""
        local = os.path.normpath(os.path.join(os.path.dirname(rel), inc)).replace(os.sep, "/")
        if m and os.path.isfile(os.path.join(root, local)):
            yield module_of(local), no
        elif inc.startswith("ssta/"):
            yield module_of("include/" + inc), no
        elif "/" in inc and os.path.isdir(os.path.join(root, "src", inc.split("/")[0])):
            yield inc.split("/")[0], no


def cycles(graph):
    """The strongly connected components of more than one module, each as a sorted list."""
    def reach(v, seen):
        for w in graph[v]:
            if w not in seen:
                seen.add(w)
                reach(w, seen)
        return seen
    reaches = {v: reach(v, set()) for v in list(graph)}
    comps = {tuple(sorted(w for w in reaches[v] if v in reaches[w])) for v in graph if v in reaches[v]}
    return sorted(list(c) for c in comps if len(c) > 1)


def walk(graph, comp):
    """A closed walk from comp[0] through every module of a strongly connected component."""
    path = [comp[0]]
    for goal in comp[1:] + comp[:1]:
        if goal in path[1:] and goal != comp[0]:
            continue
        prev, queue = {}, deque([path[-1]])
        while goal not in prev:  # breadth first, inside the component
            v = queue.popleft()
            for w in sorted(graph[v] & set(comp)):
                if w not in prev:
                    prev[w] = v
                    queue.append(w)
        step = [goal]
        while prev[step[0]] != path[-1]:
            step.insert(0, prev[step[0]])
        path += step
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap.add_argument("--max-lines", type=int, default=80, help="longest function allowed (default 80)")
    args = ap.parse_args()
    graph, where, findings = defaultdict(set), {}, 0
    for folder in FOLDERS:
        for dirpath, _, files in sorted(os.walk(os.path.join(args.root, folder))):
            for rel in sorted(os.path.relpath(os.path.join(dirpath, f), args.root).replace(os.sep, "/")
                              for f in files if f.endswith(EXTS)):
                with open(os.path.join(args.root, rel), encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                for kind, name, first, last in scopes(rel, text):
                    if kind == "func" and last - first + 1 > args.max_lines:
                        print(f"{rel}:{first}: function {name} is {last - first + 1} lines (limit {args.max_lines})")
                        findings += 1
                src = module_of(rel)
                for target, line in include_edges(args.root, rel, text) if src else ():
                    if target and target != src:
                        graph[src].add(target)
                        graph[target] |= set()
                        where.setdefault((src, target), f"{rel}:{line}")
    comps = cycles(graph)
    for comp in comps:
        edges = "; ".join(f"{a}->{b} at {where[a, b]}" for a in comp for b in sorted(graph[a]) if b in comp)
        print(f"cycle: {' -> '.join(walk(graph, comp))} ({edges})")
    print(f"summary: {findings} function(s) over {args.max_lines} lines, {len(comps)} module cycle(s)")
    return 1 if findings or comps else 0


if __name__ == "__main__":
    sys.exit(main())
