"""Every output in FOLDER is viewable and says what it is (issue 21):
  - each .xdmf parses as XML, and each of its HDF DataItems names a dataset that exists in an HDF5
    file beside it, with the shape the DataItem states (and the NumberType's kind);
  - each .h5 carries the root attributes units = "m", tool, version, command_line, created_utc;
  - each MetaImage header states `units = m`.
Usage: python3 check_outputs.py FOLDER. Exit 0 when all hold, 1 otherwise, 77 without h5py.
"""
import os
import sys
import xml.etree.ElementTree as ET

SKIP = 77
PROVENANCE = ("units", "tool", "version", "command_line", "created_utc")


def main():
    folder = sys.argv[1]
    try:
        import h5py
    except ImportError:
        print("check_outputs: skipped: h5py is not installed")
        return SKIP
    failures, items, h5s = [], 0, 0
    names = sorted(os.listdir(folder))
    for name in names:
        path = os.path.join(folder, name)
        if name.endswith(".xdmf"):
            root = ET.parse(path).getroot()  # raises on malformed XML
            if root.tag != "Xdmf":
                failures.append("%s: root element %s, not Xdmf" % (name, root.tag))
            for item in root.iter("DataItem"):
                if item.get("Format") != "HDF":
                    continue
                items += 1
                file, _, dataset = item.text.strip().partition(":")
                target = os.path.join(folder, file)
                if not os.path.isfile(target):
                    failures.append("%s: %s names %s, which is not beside it" % (name, item.text.strip(), file))
                    continue
                want = tuple(int(x) for x in item.get("Dimensions").split())
                with h5py.File(target, "r") as f:
                    if dataset not in f:
                        failures.append("%s: %s has no dataset %s" % (name, file, dataset))
                        continue
                    ds = f[dataset]
                    if ds.shape != want:
                        failures.append("%s: %s:%s has shape %s, the sidecar says %s" % (name, file, dataset, ds.shape, want))
                    kind = {"Float": "f", "Int": "i", "UInt": "u", "UChar": "u", "Char": "i"}[item.get("NumberType", "Float")]
                    if ds.dtype.kind != kind or ds.dtype.itemsize != int(item.get("Precision", "4")):
                        failures.append("%s: %s:%s is %s, the sidecar says %s %s" % (
                            name, file, dataset, ds.dtype, item.get("NumberType"), item.get("Precision")))
        elif name.endswith(".h5"):
            h5s += 1
            with h5py.File(path, "r") as f:
                for a in PROVENANCE:
                    v = f.attrs.get(a)
                    v = v.decode() if isinstance(v, bytes) else v
                    if not v:
                        failures.append("%s: no root attribute %s" % (name, a))
                if f.attrs.get("units") not in ("m", b"m"):
                    failures.append("%s: root attribute units is %r, not 'm'" % (name, f.attrs.get("units")))
        elif name.endswith(".mha") or name.endswith(".mhd"):
            with open(path, "rb") as f:
                head = f.read(4096)
            if b"\nunits = m\n" not in head:
                failures.append("%s: the header does not state units = m" % name)
    print("check_outputs: %d HDF5 files, %d XDMF data items checked in %s" % (h5s, items, folder))
    for f in failures:
        print("check_outputs: FAIL: " + f)
    if items == 0 or h5s == 0:
        print("check_outputs: FAIL: nothing to check")
        return 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
