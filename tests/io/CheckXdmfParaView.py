# Opens a bagsim results.xdmf with each of ParaView's XDMF readers and checks that every frame
# has the mesh's points and triangles and that the membrane moves between the first and the
# last frame. Run with pvpython:  pvpython CheckXdmfParaView.py OUT/results.xdmf
# (used by the optional CTest app_run_xdmf_opens_in_paraview when pvpython is installed).
import os
import sys
import xml.etree.ElementTree as ET

from paraview import servermanager as sm
from paraview import simple

path = os.path.abspath(sys.argv[1])  # Xdmf3 resolves results.h5 against the file's folder
root = ET.parse(path).getroot()
grids = root.findall("./Domain/Grid/Grid")
frames = len(grids) if grids else 1
topology = root.find(".//Topology")
cells = int(topology.get("NumberOfElements"))
points = int(root.find(".//Geometry/DataItem").get("Dimensions").split()[0])

failures = []
for name in ["Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader"]:
    if name == "XDMFReader":
        reader = simple.XDMFReader(FileNames=[path])
    else:
        reader = getattr(simple, name)(FileName=[path])
    times = list(reader.TimestepValues) if frames > 1 else [0.0]
    if len(times) != frames:
        failures.append("%s: %d time steps, expected %d" % (name, len(times), frames))
        continue
    firstLast = []
    for t in [times[0], times[-1]]:
        reader.UpdatePipeline(t)
        data = sm.Fetch(reader)
        if data.IsA("vtkCompositeDataSet"):
            it = data.NewIterator()
            it.InitTraversal()
            data = it.GetCurrentDataObject()
        if data.GetNumberOfPoints() != points or data.GetNumberOfCells() != cells:
            failures.append("%s at t=%g: %d points, %d cells; expected %d, %d" %
                            (name, t, data.GetNumberOfPoints(), data.GetNumberOfCells(),
                             points, cells))
            break
        firstLast.append([data.GetPoint(i) for i in range(points)])
    if len(firstLast) == 2 and frames > 1:
        moved = max(abs(a[k] - b[k]) for a, b in zip(*firstLast) for k in range(3))
        print("%s: %d frames, %d points, %d triangles; largest node travel %.4g m" %
              (name, frames, points, cells, moved))
        if not moved > 0.0:
            failures.append("%s: the first and last frames are identical" % name)

if failures:
    print("\n".join(failures))
    sys.exit(1)
print("ParaView reads %s with all three XDMF readers" % path)
