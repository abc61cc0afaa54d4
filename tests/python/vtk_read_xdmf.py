"""Reads an .xmf with VTK's vtkXdmfReader (the reader ParaView uses for XDMF) and prints, as JSON,
every leaf block of the last time step: its name, cell and point counts and its cell and point
arrays (name -> values as nested lists). Run by tests/python/test_output.py with a Python that has
PyPI's vtk (Debian 12's python3-vtk9 is built without vtkIOXdmf2)."""
import json
import sys

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

reader = vtkXdmfReader()
reader.SetFileName(sys.argv[1])
reader.UpdateInformation()
times = reader.GetOutputInformation(0).Get(reader.GetExecutive().TIME_STEPS()) or [0.0]
reader.UpdateTimeStep(times[-1])
out = {"times": list(times), "blocks": {}}
it = reader.GetOutputDataObject(0).NewIterator()
it.InitTraversal()
while not it.IsDoneWithTraversal():
    block = it.GetCurrentDataObject()
    name = it.GetCurrentMetaData().Get(vtkCompositeDataSet.NAME())
    arrays = {}
    for kind, data in (("cell", block.GetCellData()), ("point", block.GetPointData())):
        for i in range(data.GetNumberOfArrays()):
            arrays[f"{kind}:{data.GetArrayName(i)}"] = vtk_to_numpy(data.GetArray(i)).tolist()
    out["blocks"][name] = {"cells": block.GetNumberOfCells(), "points": block.GetNumberOfPoints(),
                           "centres": [[sum(block.GetCell(c).GetPoints().GetPoint(k)[d] for k in range(block.GetCell(c).GetNumberOfPoints())) / block.GetCell(c).GetNumberOfPoints() for d in range(3)] for c in range(block.GetNumberOfCells())],
                           "arrays": arrays}
    it.GoToNextItem()
json.dump(out, sys.stdout)
