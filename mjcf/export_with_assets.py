"""Writes a model and its file assets to a directory or a zip archive."""

from __future__ import annotations

import io
import os
import zipfile

from mjcf.element import RootElement


def _model_name(mjcf_model: RootElement) -> str:
    return mjcf_model._namescope.name


def export_with_assets(
    mjcf_model: RootElement,
    out_dir: str,
    out_file_name: str | None = None,
    *,
    precision: int = 17,
    zero_threshold: float = 0,
) -> None:
    """Writes `mjcf_model` as XML plus every asset file into `out_dir`.

    Args:
      mjcf_model: the model to export.
      out_dir: directory to write into (created if missing).
      out_file_name: name of the XML file; default '<model name>.xml'.
      precision: significant digits of floats.
      zero_threshold: floats smaller than this in magnitude are written as 0.
    """
    if not isinstance(mjcf_model, RootElement):
        raise TypeError(
            f"export_with_assets: expected an mjcf.RootElement, got {type(mjcf_model).__name__}"
        )
    if out_file_name is None:
        out_file_name = _model_name(mjcf_model) + ".xml"
    elif not out_file_name.endswith(".xml"):
        raise ValueError(
            f"export_with_assets: out_file_name must end in '.xml', got {out_file_name!r}"
        )
    os.makedirs(out_dir, exist_ok=True)
    xml = mjcf_model.to_xml_string(precision=precision, zero_threshold=zero_threshold)
    files = dict(mjcf_model.get_assets())
    files[out_file_name] = xml.encode("utf-8")
    for name, contents in files.items():
        with open(os.path.join(out_dir, name), "wb") as handle:
            handle.write(contents)


def export_with_assets_as_zip(
    mjcf_model: RootElement,
    out_dir: str,
    model_name: str | None = None,
    *,
    precision: int = 17,
    zero_threshold: float = 0,
) -> None:
    """Writes '<out_dir>/<model_name>.zip' holding folder '<model_name>/' with XML and assets."""
    if not isinstance(mjcf_model, RootElement):
        raise TypeError(
            "export_with_assets_as_zip: expected an mjcf.RootElement, got "
            f"{type(mjcf_model).__name__}"
        )
    if model_name is None:
        model_name = _model_name(mjcf_model)
    xml = mjcf_model.to_xml_string(precision=precision, zero_threshold=zero_threshold)
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr(os.path.join(model_name, model_name + ".xml"), xml)
        for name, contents in mjcf_model.get_assets().items():
            archive.writestr(os.path.join(model_name, name), contents)
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, model_name + ".zip"), "wb") as handle:
        handle.write(buffer.getvalue())
