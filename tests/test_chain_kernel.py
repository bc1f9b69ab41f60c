"""The compiled chain step (ssw.chain.kernel): it is used only when built from the source in
the tree, and says how to rebuild it otherwise."""

import pytest

from ssw.chain import kernel
from ssw.errors import SswError


def test_a_library_built_from_another_source_is_refused(tmp_path, monkeypatch):
    """An edited ``_step.c`` whose library was not rebuilt would run old arithmetic under
    new docs: the loader compares the hash built into the library with the source's and
    refuses, naming the command that rebuilds it."""
    edited = tmp_path / "_step.c"
    edited.write_bytes(kernel.SOURCE.read_bytes() + b"\n/* edited */\n")
    monkeypatch.setattr(kernel, "SOURCE", edited)
    with pytest.raises(SswError, match=r"built from another _step.c .*scripts/setup.sh"):
        kernel.library.__wrapped__()


def test_the_library_in_the_tree_is_the_source_in_the_tree():
    """The library the tests run was built from the ``_step.c`` beside it."""
    lib = kernel.library()
    assert lib.ssw_step_source().decode() == kernel.source_digest()
