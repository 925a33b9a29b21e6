"""The array code of the suite's domains: one module per dm_control suite domain, named for
it, each registering its `SuiteBatchTask`s with `suite_batch.tasks.register` when imported
(`suite_batch` imports them all)."""
