#!/usr/bin/env python3
"""Checks and conversions for scripts/fetch-data (see docs/DATA.md).

Subcommands:
  nrrd   FILE DIMS TYPE        check a NRRD header (stdlib only)
  nifti  FILE DIMS TYPE        check a NIfTI-1 header (stdlib only)
  envmaps SRC DST              write OpenEXR's decode of each EXR in SRC to DST, ZIP
                               compressed, checked bit for bit (needs numpy, OpenEXR)
  convert NRRD OUT             write lung1 in other formats and verify them (needs numpy,
                               SimpleITK, pydicom, vtk)

DIMS is like 512x512x48 (x fastest). Everything here fails loudly: any mismatch raises,
and the exit status is non-zero.
"""

import gzip
import struct
import sys
from pathlib import Path


def fail(msg):
    sys.exit(f"fetch-data: ERROR: {msg}")


def parse_dims(text):
    return tuple(int(v) for v in text.split("x"))


# ---------------------------------------------------------------------------------------
# NRRD (only what the pyradiomics files use: one attached, gzip or raw, data block)

NRRD_TYPES = {"short": "int16", "int16": "int16", "signed short": "int16",
              "unsigned char": "uint8", "uchar": "uint8", "float": "float32"}


def read_nrrd_header(path):
    raw = Path(path).read_bytes()
    end = raw.find(b"\n\n")
    if not raw.startswith(b"NRRD") or end < 0:
        fail(f"{path}: not a NRRD file")
    fields = {}
    for line in raw[:end].decode("ascii").splitlines()[1:]:
        if line.startswith("#") or ":" not in line:
            continue
        key, _, value = line.partition(":")
        fields[key.strip()] = value.lstrip("=").strip()
    return fields, raw[end + 2:]


def nrrd_array(path):
    """The voxels as a numpy array indexed [z, y, x] (x fastest, as stored), by our own
    parser: the reference every converted copy is compared against."""
    import numpy as np

    fields, body = read_nrrd_header(path)
    dims = tuple(int(v) for v in fields["sizes"].split())
    dtype = NRRD_TYPES[fields["type"]]
    if fields.get("encoding") in ("gzip", "gz"):
        body = gzip.decompress(body)
    elif fields.get("encoding") != "raw":
        fail(f"{path}: unsupported NRRD encoding {fields.get('encoding')}")
    order = "<" if fields.get("endian", "little") == "little" else ">"
    a = np.frombuffer(body, dtype=np.dtype(dtype).newbyteorder(order))
    if a.size != dims[0] * dims[1] * dims[2]:
        fail(f"{path}: {a.size} voxels, header says {dims}")
    # NRRD: the first axis in 'sizes' is the fastest; numpy C order wants it last.
    return fields, a.astype(dtype).reshape(dims[::-1])


def cmd_nrrd(path, dims, typ):
    fields, _ = read_nrrd_header(path)
    got_dims = tuple(int(v) for v in fields.get("sizes", "").split())
    got_type = NRRD_TYPES.get(fields.get("type"), fields.get("type"))
    if got_dims != parse_dims(dims) or got_type != typ or fields.get("dimension") != "3":
        fail(f"{path}: expected {dims} {typ}, header says sizes {got_dims} type {got_type}")
    print(f"  ok {Path(path).name}: {dims} {typ}, spacing from "
          f"'space directions: {fields.get('space directions')}'")


# ---------------------------------------------------------------------------------------
# NIfTI-1

NIFTI_TYPES = {2: "uint8", 4: "int16", 8: "int32", 16: "float32", 512: "uint16"}


def cmd_nifti(path, dims, typ):
    with gzip.open(path) if path.endswith(".gz") else open(path, "rb") as f:
        hdr = f.read(348)
    if struct.unpack("<i", hdr[:4])[0] != 348 or hdr[344:348] not in (b"n+1\0", b"ni1\0"):
        fail(f"{path}: not a little-endian NIfTI-1 file")
    dim = struct.unpack("<8h", hdr[40:56])
    datatype = struct.unpack("<h", hdr[70:72])[0]
    pixdim = struct.unpack("<8f", hdr[76:108])
    got = tuple(dim[1:1 + dim[0]])
    got_type = NIFTI_TYPES.get(datatype, f"datatype {datatype}")
    if got != parse_dims(dims) or got_type != typ:
        fail(f"{path}: expected {dims} {typ}, header says {got} {got_type}")
    print(f"  ok {Path(path).name}: {dims} {typ}, voxel {pixdim[1]:g}x{pixdim[2]:g}x{pixdim[3]:g} mm")


# ---------------------------------------------------------------------------------------
# Environment maps

def cmd_envmaps(src, dst):
    import numpy as np
    import OpenEXR

    src, dst = Path(src), Path(dst)
    files = sorted(src.glob("*.exr"))
    if not files:
        fail(f"{src}: no .exr files")
    for path in files:
        f = OpenEXR.File(str(path))
        header, channels = f.header(), f.channels()
        if "RGB" not in channels:
            fail(f"{path}: expected R, G, B channels, found {sorted(channels)}")
        rgb = channels["RGB"].pixels
        if rgb.shape != (512, 1024, 3) or rgb.dtype != np.float32:
            fail(f"{path}: expected 1024x512 float32 RGB, found {rgb.shape} {rgb.dtype}")
        out = dst / path.name
        new_header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        OpenEXR.File(new_header, {"RGB": rgb}).write(str(out))
        g = OpenEXR.File(str(out))
        back, comp = g.channels()["RGB"].pixels, g.header()["compression"]
        if not np.array_equal(back, rgb) or comp != OpenEXR.ZIP_COMPRESSION:
            fail(f"{out}: re-read pixels differ from {path}")
        print(f"  ok {out.name}: 1024x512 float32 RGB, {header['compression'].name} -> "
              f"{comp.name}, range [{rgb.min():.4g}, {rgb.max():.4g}]")


# ---------------------------------------------------------------------------------------
# lung1 in other formats

def check_same(name, ref, got):
    import numpy as np

    got = np.asarray(got)
    if got.shape != ref.shape or not np.array_equal(got, ref):
        diff = "shape " + str(got.shape) if got.shape != ref.shape else \
            f"{int((got != ref).sum())} voxels differ"
        fail(f"{name}: voxel array differs from the NRRD's ({diff})")
    print(f"  ok {name}: {ref.shape[2]}x{ref.shape[1]}x{ref.shape[0]} {ref.dtype}, "
          f"identical to the NRRD")


def check_geometry(name, image, spacing, origin):
    import numpy as np

    if not (np.allclose(image.GetSpacing(), spacing, atol=1e-4)
            and np.allclose(image.GetOrigin(), origin, atol=1e-3)
            and np.allclose(image.GetDirection(), np.eye(3).ravel(), atol=1e-6)):
        fail(f"{name}: geometry differs: spacing {image.GetSpacing()} origin "
             f"{image.GetOrigin()} direction {image.GetDirection()}, expected spacing "
             f"{spacing} origin {origin} identity direction")


def write_dicom_series(ref, spacing, origin, out):
    """One CT Image Storage file per slice, explicit VR little endian, uncompressed.
    Stored values are HU + 1024 (unsigned, 12 bits stored in 16), with RescaleSlope 1 and
    RescaleIntercept -1024, as CT scanners commonly write them."""
    import numpy as np
    import pydicom
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import CTImageStorage, ExplicitVRLittleEndian, generate_uid

    out.mkdir(parents=True, exist_ok=True)
    intercept = -1024
    stored = (ref.astype(np.int32) - intercept)
    if stored.min() < 0 or stored.max() > 4095:
        fail("lung1 values do not fit 12 unsigned bits after the -1024 intercept")
    stored = stored.astype("<u2")
    # Deterministic UIDs (pydicom's root + a hash of these strings): reruns give the same files.
    study = generate_uid(entropy_srcs=["refrakt", "lung1", "study"])
    series = generate_uid(entropy_srcs=["refrakt", "lung1", "series"])
    frame = generate_uid(entropy_srcs=["refrakt", "lung1", "frame"])
    nz, ny, nx = ref.shape
    for k in range(nz):
        sop = generate_uid(entropy_srcs=["refrakt", "lung1", "slice", str(k)])
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CTImageStorage
        meta.MediaStorageSOPInstanceUID = sop
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = Dataset()
        ds.file_meta = meta
        ds.SOPClassUID = CTImageStorage
        ds.SOPInstanceUID = sop
        ds.SpecificCharacterSet = "ISO_IR 100"
        ds.ImageType = ["DERIVED", "SECONDARY", "AXIAL"]
        ds.Modality = "CT"
        ds.Manufacturer = "refrakt scripts/fetch-data"
        ds.PatientName = "Lung1^Pyradiomics"
        ds.PatientID = "pyradiomics-lung1"
        ds.StudyInstanceUID = study
        ds.SeriesInstanceUID = series
        ds.FrameOfReferenceUID = frame
        ds.StudyID = "1"
        ds.SeriesNumber = 1
        ds.InstanceNumber = k + 1
        ds.SeriesDescription = "pyradiomics 3.1.0 data/lung1_image.nrrd"
        ds.PositionReferenceIndicator = ""
        # NRRD space is left-posterior-superior, the same as DICOM's patient coordinates.
        ds.ImagePositionPatient = [f"{origin[0]:.6g}", f"{origin[1]:.6g}",
                                   f"{origin[2] + k * spacing[2]:.6g}"]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.SliceThickness = f"{spacing[2]:.6g}"
        ds.SpacingBetweenSlices = f"{spacing[2]:.6g}"
        ds.SliceLocation = f"{origin[2] + k * spacing[2]:.6g}"
        ds.PixelSpacing = [f"{spacing[1]:.8g}", f"{spacing[0]:.8g}"]  # row, column spacing
        ds.SamplesPerPixel = 1
        ds.PhotometricInterpretation = "MONOCHROME2"
        ds.Rows = ny
        ds.Columns = nx
        ds.BitsAllocated = 16
        ds.BitsStored = 12
        ds.HighBit = 11
        ds.PixelRepresentation = 0
        ds.RescaleIntercept = str(intercept)
        ds.RescaleSlope = "1"
        ds.RescaleType = "HU"
        ds.WindowCenter = "-600"
        ds.WindowWidth = "1500"
        ds.PixelData = stored[k].tobytes()
        ds.save_as(out / f"slice_{k + 1:03d}.dcm", enforce_file_format=True)
    return series


def write_vti(ref, spacing, origin, path):
    """vtkXMLImageDataWriter, appended data, base64 encoded, zlib compressed."""
    import vtkmodules.vtkCommonDataModel as dm
    import vtkmodules.vtkIOXML as xml
    from vtkmodules.util import numpy_support

    nz, ny, nx = ref.shape
    image = dm.vtkImageData()
    image.SetDimensions(nx, ny, nz)
    image.SetSpacing(*spacing)
    image.SetOrigin(*origin)
    scalars = numpy_support.numpy_to_vtk(ref.ravel(order="C"), deep=True)
    scalars.SetName("lung1")
    image.GetPointData().SetScalars(scalars)
    w = xml.vtkXMLImageDataWriter()
    w.SetFileName(str(path))
    w.SetInputData(image)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOn()
    w.SetCompressorTypeToZLib()
    w.SetHeaderTypeToUInt64()
    if w.Write() != 1:
        fail(f"{path}: vtkXMLImageDataWriter failed")


def read_vti(path):
    import vtkmodules.vtkIOXML as xml
    from vtkmodules.util import numpy_support

    r = xml.vtkXMLImageDataReader()
    r.SetFileName(str(path))
    r.Update()
    image = r.GetOutput()
    nx, ny, nz = image.GetDimensions()
    a = numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
    return image, a.reshape(nz, ny, nx)


def cmd_convert(nrrd, out):
    import numpy as np
    import SimpleITK as sitk

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fields, ref = nrrd_array(nrrd)
    nz, ny, nx = ref.shape
    print(f"  reference: {nrrd} parsed directly, {nx}x{ny}x{nz} {ref.dtype} "
          f"(x fastest), range [{ref.min()}, {ref.max()}]")

    from_nrrd = sitk.ReadImage(str(nrrd))
    check_same("SimpleITK reading the NRRD", ref, sitk.GetArrayViewFromImage(from_nrrd))
    spacing, origin = from_nrrd.GetSpacing(), from_nrrd.GetOrigin()
    check_geometry("SimpleITK reading the NRRD", from_nrrd, spacing, origin)
    # A fresh image from our array, with the geometry only: no NRRD metadata is carried
    # into the other formats' headers.
    image = sitk.GetImageFromArray(ref)
    image.CopyInformation(from_nrrd)

    # MetaImage, one file, zlib compressed.
    sitk.WriteImage(image, str(out / "lung1.mha"), useCompression=True)
    header = (out / "lung1.mha").read_bytes()[:2000]
    if b"CompressedData = True" not in header or b"ElementDataFile = LOCAL" not in header:
        fail("lung1.mha: expected a compressed MetaImage with local data")
    back = sitk.ReadImage(str(out / "lung1.mha"))
    check_geometry("lung1.mha", back, spacing, origin)
    check_same("lung1.mha", ref, sitk.GetArrayViewFromImage(back))

    # MetaImage, header + uncompressed raw.
    sitk.WriteImage(image, str(out / "lung1.mhd"), useCompression=False)
    if b"ElementDataFile = lung1.raw" not in (out / "lung1.mhd").read_bytes():
        fail("lung1.mhd: expected ElementDataFile = lung1.raw")
    if (out / "lung1.raw").read_bytes() != ref.astype("<i2").tobytes():
        fail("lung1.raw: bytes differ from the NRRD's voxels (x fastest, little endian)")
    back = sitk.ReadImage(str(out / "lung1.mhd"))
    check_geometry("lung1.mhd", back, spacing, origin)
    check_same("lung1.mhd + lung1.raw", ref, sitk.GetArrayViewFromImage(back))

    # NIfTI-1, gzip compressed (ITK writes LPS geometry as RAS qform/sform).
    sitk.WriteImage(image, str(out / "lung1.nii.gz"))
    back = sitk.ReadImage(str(out / "lung1.nii.gz"))
    check_geometry("lung1.nii.gz", back, spacing, origin)
    check_same("lung1.nii.gz", ref, sitk.GetArrayViewFromImage(back))
    cmd_nifti(str(out / "lung1.nii.gz"), f"{nx}x{ny}x{nz}", "int16")

    # Open SciVis style raw: name_WxHxD_type.raw, x fastest, little endian, no header.
    raw = out / f"lung1_{nx}x{ny}x{nz}_int16.raw"
    raw.write_bytes(ref.astype("<i2").tobytes())
    check_same(raw.name, ref, np.fromfile(raw, dtype="<i2").reshape(nz, ny, nx))

    # VTK XML image data.
    write_vti(ref, spacing, origin, out / "lung1.vti")
    head = (out / "lung1.vti").read_bytes()[:1000]
    for needle in (b'compressor="vtkZLibDataCompressor"', b'header_type="UInt64"',
                   b'format="appended"', b'encoding="base64"'):
        if needle not in head:
            fail(f"lung1.vti: header lacks {needle.decode()}")
    vimage, varr = read_vti(out / "lung1.vti")
    if not (np.allclose(vimage.GetSpacing(), spacing) and np.allclose(vimage.GetOrigin(), origin)):
        fail(f"lung1.vti: geometry differs: {vimage.GetSpacing()} {vimage.GetOrigin()}")
    check_same("lung1.vti (vtkXMLImageDataReader)", ref, varr)

    # DICOM series.
    dicom_dir = out / "lung1_dicom"
    if dicom_dir.exists():
        for f in dicom_dir.glob("*.dcm"):
            f.unlink()
    series = write_dicom_series(ref, spacing, origin, dicom_dir)
    import pydicom
    from pydicom.pixels import apply_rescale

    slices = [pydicom.dcmread(f) for f in sorted(dicom_dir.glob("*.dcm"))]
    slices.sort(key=lambda d: float(d.ImagePositionPatient[2]))
    if len(slices) != nz or {d.SeriesInstanceUID for d in slices} != {series}:
        fail("lung1_dicom: wrong slice count or series UID")
    if any(d.file_meta.TransferSyntaxUID != pydicom.uid.ExplicitVRLittleEndian for d in slices):
        fail("lung1_dicom: not explicit VR little endian")
    hu = np.stack([apply_rescale(d.pixel_array, d) for d in slices])
    check_same("lung1_dicom (pydicom, rescaled)", ref, hu.astype(np.int16))
    reader = sitk.ImageSeriesReader()
    reader.SetFileNames(sitk.ImageSeriesReader.GetGDCMSeriesFileNames(str(dicom_dir), series))
    back = reader.Execute()
    check_geometry("lung1_dicom (SimpleITK/GDCM)", back, spacing, origin)
    check_same("lung1_dicom (SimpleITK/GDCM)", ref,
               sitk.GetArrayViewFromImage(back).astype(np.int16))


def main(argv):
    if len(argv) >= 4 and argv[0] == "nrrd":
        cmd_nrrd(argv[1], argv[2], argv[3])
    elif len(argv) >= 4 and argv[0] == "nifti":
        cmd_nifti(argv[1], argv[2], argv[3])
    elif len(argv) == 3 and argv[0] == "envmaps":
        cmd_envmaps(argv[1], argv[2])
    elif len(argv) == 3 and argv[0] == "convert":
        cmd_convert(argv[1], argv[2])
    else:
        fail(__doc__)


if __name__ == "__main__":
    main(sys.argv[1:])
