"""The import graph of src/render/: which first-level module of render/ names which
other (`crate::render::x`, `super::x`, a folder declared with `#[path]`), its cycles, and
which modules name each optical model. Tests and the facade's `pub use` re-exports in
render/mod.rs are left out. Issue 34's closing note shows it before and after.
Usage: python3 scripts/render-imports.py [SRC_DIR, default src]"""
import os, re, sys
src = sys.argv[1] if len(sys.argv) > 1 else 'src'
root = os.path.join(src, 'render')
def modpath(f):
    rel = os.path.relpath(f, src)[:-3].split(os.sep)
    if rel[-1] in ('mod',): rel = rel[:-1]
    return rel  # e.g. ['render','ao'] or ['render','ao','table']
edges = {}
MODS = {n[:-3] if n.endswith('.rs') else n for n in os.listdir(root)} - {'mod'}

def top(parts):
    if not parts or parts[0] != 'render': return None
    if len(parts) == 1: return '(render)'
    return parts[1] if parts[1] in MODS else '(render)'
def strip_tests(s):
    i = s.find('#[cfg(test)]\nmod tests')
    return s if i < 0 else s[:i]
for d, _, fs in os.walk(root):
    for n in fs:
        if not n.endswith('.rs'): continue
        f = os.path.join(d, n)
        me = modpath(f)
        # a file that is not mod.rs is its own module; for super:: the parent is me[:-1]
        s = strip_tests(open(f).read())
        s = re.sub(r'//[^\n]*', '', s)
        src_top = top(me)
        if src_top is None: continue
        targets = set()
        def add(base, rest):
            # rest: text after the prefix: ident or {a, b::c}
            rest = rest.strip()
            if rest.startswith('{'):
                depth = 0; body = ''
                for ch in rest:
                    if ch == '{': depth += 1
                    if ch == '}': depth -= 1
                    body += ch
                    if depth == 0: break
                items = re.findall(r'(?:^|[{,])\s*(\w+)', body)
            else:
                m = re.match(r'(\w+|\*)', rest); items = [m.group(1)] if m else []
            for it in items:
                if it == '*':  # a glob: the module itself
                    targets.add(top(base) if len(base) > 1 else '(render)'); continue
                if it in ('self',):
                    targets.add(top(base + ['x']) if len(base) == 1 else top(base)); continue
                p = base + [it]
                t = top(p)
                if t: targets.add(t)
        for m in re.finditer(r'crate::render::(\{[^;]*|\w+)', s):
            add(['render'], m.group(1))
        for m in re.finditer(r'(?<![:\w])((?:super::)+)(\{[^;]*|\w+|\*)', s):
            k = m.group(1).count('super::')
            parent = me[:-k] if k <= len(me) else []
            add(parent, m.group(2))
        # a folder declared elsewhere with #[path] (the registry declares the models)
        for m in re.finditer(r'#\[path = "(\w+)/mod\.rs"\]', s):
            if m.group(1) in MODS: targets.add(m.group(1))
        if me == ['render']:
            # the facade's re-exports (`pub use x::Y;`) are the crate's public API, not a
            # dependency of the renderer's code
            s = re.sub(r'pub(\(crate\))? use [^;]*;', '', s)
            for m in re.finditer(r'(?<![:\w])(\w+)::', s):
                if m.group(1) in MODS: targets.add(m.group(1))
        for t in targets:
            if t and t != src_top:
                edges.setdefault(src_top, set()).add(t)
mods = sorted(set(edges) | {t for v in edges.values() for t in v})
models = {'ea','ao','single','ambient','refract'}
n = sum(len(v) for v in edges.values())
print(f"{n} edges among {len(mods)} modules of render/")
for m in sorted(edges):
    print(f"  {m} -> {', '.join(sorted(edges[m]))}")
# cycles (strongly connected components)
idx = {}; low = {}; st = []; on = set(); comps = []; c = [0]
def sc(v):
    idx[v] = low[v] = c[0]; c[0] += 1; st.append(v); on.add(v)
    for w in edges.get(v, ()):
        if w not in idx: sc(w); low[v] = min(low[v], low[w])
        elif w in on: low[v] = min(low[v], idx[w])
    if low[v] == idx[v]:
        comp = []
        while True:
            w = st.pop(); on.discard(w); comp.append(w)
            if w == v: break
        if len(comp) > 1: comps.append(sorted(comp))
for v in mods:
    if v not in idx: sc(v)
print("import cycles:", comps if comps else "none")
into = {m: sorted(k for k, v in edges.items() if m in v) for m in models}
for m in sorted(models):
    print(f"  model {m} is named by: {', '.join(into[m]) or 'nothing'}")
