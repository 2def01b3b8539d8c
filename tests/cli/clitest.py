# SPDX-License-Identifier: Apache-2.0
"""clitest.py - the harness the `trn` command-line tests share.

A Harness runs build/<preset>/trn (optionally with a fixed subcommand in front
of every call), counts checks, records failures, and checks the error
convention of bad input: the given exit code, exactly one stderr line
`trn <cmd>: <reason>` holding an expected phrase, and nothing on stdout.
Every JSON object read through run_json must carry "version", equal to what
`trn --version` prints (check_version for objects read otherwise).
"""
import json
import subprocess


class Harness:
    def __init__(self, trn, sub=(), timeout=300):
        self.trn = trn
        self.sub = [str(a) for a in sub]
        self.timeout = timeout
        self.checks = 0
        self.failures = []
        self._version = None

    def version(self):
        """The version `trn --version` prints ("trn X.Y.Z" -> "X.Y.Z"), read once."""
        if self._version is None:
            p = subprocess.run([self.trn, "--version"], capture_output=True, text=True,
                               timeout=self.timeout)
            words = p.stdout.split()
            ok = p.returncode == 0 and len(words) == 2 and words[0] == "trn"
            self.check(ok, f"trn --version: exit {p.returncode}, {p.stdout!r}")
            self._version = words[1] if ok else "?"
        return self._version

    def check_version(self, obj, label):
        """obj (a parsed JSON object of trn) carries "version" = trn --version's."""
        self.check(isinstance(obj, dict) and obj.get("version") == self.version(),
                   f"{label}: JSON \"version\" {obj.get('version') if isinstance(obj, dict) else None!r}, "
                   f"want {self.version()!r}")

    def check(self, cond, what):
        self.checks += 1
        if not cond:
            self.failures.append(what)
            print("FAIL:", what)

    def run(self, *args, timeout=None):
        p = subprocess.run([self.trn] + self.sub + [str(a) for a in args], capture_output=True,
                           text=True, timeout=timeout or self.timeout)
        return p.returncode, p.stdout, p.stderr

    def expect_error(self, rc_want, needle, *args):
        rc, out, err = self.run(*args)
        words = self.sub + [str(a) for a in args]
        label = "trn " + " ".join(words)
        lines = err.splitlines()
        self.check(rc == rc_want, f"{label}: exit {rc}, want {rc_want} (stderr: {err.strip()!r})")
        self.check(len(lines) == 1, f"{label}: {len(lines)} stderr lines, want 1: {err!r}")
        self.check(err.startswith(f"trn {words[0]}: "),
                   f"{label}: message does not start with 'trn {words[0]}: ': {err!r}")
        self.check(needle in err, f"{label}: message lacks {needle!r}: {err!r}")
        self.check(out == "", f"{label}: stdout not empty: {out!r}")

    def run_json(self, *args):
        """A run that must succeed and print exactly one line of JSON; returns the object."""
        rc, out, err = self.run(*args)
        label = "trn " + " ".join(self.sub + [str(a) for a in args])
        self.check(rc == 0, f"{label}: exit {rc}: {err.strip()}")
        try:
            obj = json.loads(out)
        except ValueError:
            self.check(False, f"{label}: stdout is not one JSON object: {out!r}")
            return {}
        self.check(out.count("\n") == 1, f"{label}: JSON is not one line")
        self.check_version(obj, label)
        return obj

    def finish(self, name=""):
        """Print the tally; return the exit status (1 if any check failed)."""
        print(f"{name + ': ' if name else ''}{self.checks} checks, {len(self.failures)} failed")
        return 1 if self.failures else 0


def write_raster(path, arr, gt, fmt="GTiff", nodata=None, srs=None):
    """Write a float32 one-band raster through a MEM dataset (any GDAL driver with CreateCopy)."""
    from osgeo import gdal  # only the tests that write rasters need GDAL

    mem = gdal.GetDriverByName("MEM").Create("", arr.shape[1], arr.shape[0], 1, gdal.GDT_Float32)
    if gt is not None:
        mem.SetGeoTransform(gt)
    if srs:
        mem.SetProjection(srs)
    band = mem.GetRasterBand(1)
    if nodata is not None:
        band.SetNoDataValue(nodata)
    band.WriteArray(arr)
    gdal.GetDriverByName(fmt).CreateCopy(path, mem)
    mem = None
