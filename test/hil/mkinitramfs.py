#!/usr/bin/python3
"""The bench's initramfs: busybox-static, the guest init and the kernel modules it loads.

  mkinitramfs.py --modules-root ROOT --kver KVER --busybox /bin/busybox --init test/hil/init \
                 --out initramfs.cpio.gz [--ship MODULE]... [--extra-ko PATH.ko]... \
                 [--file NAME=PATH]... MODULE...

ROOT is the unpacked kernel package (`dpkg -x`): ROOT/lib/modules/KVER/kernel/**.ko. Each MODULE and
every module it depends on (the `depends=` field of the module's own .modinfo section, as depmod reads
it; the package has no modules.dep, depmod runs at install) is copied into the archive, and
/modules.load lists them in load order (dependencies first), /modules.ship the ones only shipped. A module the kernel has built in
(modules.builtin) is left out.
--ship MODULE: the module is copied but not listed in /modules.load (a scenario loads it with its own
parameters, e.g. vivid); its dependencies are loaded at boot. --extra-ko PATH: a module built out of
tree (gpio-sim); its depends= are resolved in the package, and it is loaded after them. --file
NAME=PATH: PATH's content as /NAME (e.g. the reason gpio-sim could not be built). Written as a newc cpio (what the kernel unpacks), gzip-compressed, every
entry owned by root, so no cpio tool and no root are needed to build it.
"""
import argparse
import gzip
import os
import stat
import sys


def norm(name):
    return name.replace("-", "_")


def index_modules(moddir):
    """module name (normalised) -> path of its .ko below moddir/kernel."""
    found = {}
    for dirpath, _, files in os.walk(os.path.join(moddir, "kernel")):
        for f in files:
            if f.endswith(".ko"):
                found[norm(f[:-3])] = os.path.join(dirpath, f)
    return found


def builtin_modules(moddir):
    names = set()
    path = os.path.join(moddir, "modules.builtin")
    if os.path.exists(path):
        with open(path) as fh:
            for line in fh:
                base = os.path.basename(line.strip())
                if base.endswith(".ko"):
                    names.add(norm(base[:-3]))
    return names


def modinfo_depends(path):
    """The comma-separated depends= of a module's .modinfo strings (NUL-separated key=value)."""
    with open(path, "rb") as fh:
        data = fh.read()
    for field in data.split(b"\0"):
        if field.startswith(b"depends="):
            value = field[len(b"depends="):].decode()
            return [d for d in value.split(",") if d]
    return []


def load_order(wanted, index, builtin):
    order, state = [], {}

    def visit(name, chain):
        n = norm(name)
        if n in builtin:
            return
        if state.get(n) == "done":
            return
        if state.get(n) == "visiting":
            sys.exit("mkinitramfs: dependency cycle: " + " -> ".join(chain + [name]))
        if n not in index:
            sys.exit(f"mkinitramfs: module {name} is neither in the package nor built in"
                     + (f" (needed by {chain[-1]})" if chain else ""))
        state[n] = "visiting"
        for dep in modinfo_depends(index[n]):
            visit(dep, chain + [name])
        state[n] = "done"
        order.append(n)

    for w in wanted:
        visit(w, [])
    return order


class Cpio:
    """newc ("070701") archive writer."""

    def __init__(self):
        self.parts = []
        self.ino = 1

    def _entry(self, name, mode, data=b"", rdev=(0, 0), nlink=1):
        fields = [self.ino, mode, 0, 0, nlink, 0, len(data), 0, 0, rdev[0], rdev[1], len(name) + 1, 0]
        self.ino += 1
        hdr = b"070701" + b"".join(b"%08X" % v for v in fields)
        blob = hdr + name.encode() + b"\0"
        blob += b"\0" * (-len(blob) % 4)
        blob += data + b"\0" * (-len(data) % 4)
        self.parts.append(blob)

    def dir(self, name):
        self._entry(name, stat.S_IFDIR | 0o755, nlink=2)

    def file(self, name, data, mode=0o644):
        self._entry(name, stat.S_IFREG | mode, data)

    def symlink(self, name, target):
        self._entry(name, stat.S_IFLNK | 0o777, target.encode())

    def chardev(self, name, major, minor):
        self._entry(name, stat.S_IFCHR | 0o600, rdev=(major, minor))

    def bytes(self):
        self._entry("TRAILER!!!", 0)
        return b"".join(self.parts)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--modules-root", required=True)
    ap.add_argument("--kver", required=True)
    ap.add_argument("--busybox", required=True)
    ap.add_argument("--init", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--ship", action="append", default=[])
    ap.add_argument("--extra-ko", action="append", default=[])
    ap.add_argument("--file", action="append", default=[])
    ap.add_argument("modules", nargs="+")
    a = ap.parse_args()

    moddir = os.path.join(a.modules_root, "lib", "modules", a.kver)
    index = index_modules(moddir)
    if not index:
        sys.exit(f"mkinitramfs: no module below {moddir}/kernel")
    builtin = builtin_modules(moddir)
    extra = {}
    for path in a.extra_ko:
        n = norm(os.path.basename(path)[:-3])
        if n in index:
            sys.exit(f"mkinitramfs: {path}: the package has a module of that name already")
        extra[n] = path
    index.update(extra)
    order = load_order(a.modules + list(extra) + a.ship, index, builtin)
    shipped_only = {norm(m) for m in a.ship} - set(load_order(a.modules + list(extra), index, builtin))

    c = Cpio()
    for d in ("bin", "dev", "proc", "sys", "host", "lib", "lib/modules"):
        c.dir(d)
    c.chardev("dev/console", 5, 1)
    c.chardev("dev/null", 1, 3)
    with open(a.busybox, "rb") as fh:
        c.file("bin/busybox", fh.read(), 0o755)
    c.symlink("bin/sh", "busybox")
    with open(a.init, "rb") as fh:
        c.file("init", fh.read(), 0o755)
    load, ship = [], []
    for n in order:
        base = os.path.basename(index[n])
        with open(index[n], "rb") as fh:
            c.file("lib/modules/" + base, fh.read())
        (ship if n in shipped_only else load).append(base)
    c.file("modules.load", ("\n".join(load) + "\n").encode())
    c.file("modules.ship", ("\n".join(ship) + "\n").encode())
    for spec in a.file:
        name, path = spec.split("=", 1)
        with open(path, "rb") as fh:
            c.file(name, fh.read())
    c.file("kver", (a.kver + "\n").encode())

    tmp = a.out + ".tmp"
    with open(tmp, "wb") as fh:
        fh.write(gzip.compress(c.bytes(), compresslevel=6, mtime=0))
    os.replace(tmp, a.out)
    print(f"mkinitramfs: {a.out}: busybox + {len(load)} modules loaded at boot: {' '.join(load)}"
          + (f"; shipped for the scenarios: {' '.join(ship)}" if ship else ""))


if __name__ == "__main__":
    main()
