from gyrolab.app import main

main()
