"""Exchange with other NVH tools: a store's runs and fitted results as UFF dataset 58.

The reading side is a record reader (:mod:`rattle_lab.records._readers.uff`), so that
``rattle-lab ingest`` takes ``.uff`` files like any other format.
"""

from ._uff import UFF_TYPE_OF_QUANTITY, export_uff, uff_sets

__all__ = ["UFF_TYPE_OF_QUANTITY", "export_uff", "uff_sets"]
