"""The evaluator networks of the papers' protocol: text-motion evaluator, action classifiers, ST-GCN."""
