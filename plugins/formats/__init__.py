"""Built-in dataset formats (``register_dataset_formats``): one module per set, each registered
exactly as a third party's format is."""
